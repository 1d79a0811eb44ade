#include "cellwalk/scene/scene_file.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

Object make_object(ObjectId id, Random& rng, bool colors) {
  Object o;
  o.id = id;
  o.name = "object-" + std::to_string(id);
  o.color = static_cast<Rgba8>(rng.next());
  const int n = static_cast<int>(rng.integer(3, 12));
  for (int i = 0; i < n; ++i)
    o.mesh.positions.push_back(Vec3(rng.uniform(-5, 5), rng.uniform(0, 9), rng.uniform(-5, 5)));
  for (int t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) o.mesh.indices.push_back(static_cast<uint32_t>(rng.integer(0, n - 1)));
  compute_normals(o.mesh);
  if (colors) o.mesh.colors.assign(o.mesh.positions.size(), rgba8(1, 2, 3));
  o.bounds = bounds_of(o.mesh);
  return o;
}

std::vector<Object> write_scene(const std::string& file, int count, uint64_t seed = 7) {
  Random rng(seed);
  std::vector<Object> objects;
  SceneWriter writer(file);
  for (int i = 0; i < count; ++i) {
    objects.push_back(make_object(static_cast<ObjectId>(i), rng, i % 2 == 1));
    writer.add(objects.back());
  }
  SceneInfo info;
  info.generator = "test";
  info.seed = seed;
  info.nav.nodes = {Vec3(0, 1.7f, 0), Vec3(10, 1.7f, 0)};
  info.nav.edges = {{0, 1}};
  writer.finish(info);
  return objects;
}

using test::slurp;
using test::spit;

TEST(SceneFile, RoundTripsObjectsAndInfo) {
  test::TempDir dir;
  const std::string file = dir.file("a.cwscene");
  auto objects = write_scene(file, 25);
  SceneReader reader(file);
  ASSERT_EQ(reader.object_count(), objects.size());
  EXPECT_EQ(reader.info().generator, "test");
  EXPECT_EQ(reader.info().seed, 7u);
  ASSERT_EQ(reader.info().nav.edges.size(), 1u);
  uint64_t triangles = 0;
  Aabb bounds;
  for (const Object& expected : objects) {
    Object got = reader.read_object(expected.id);
    EXPECT_EQ(got.name, expected.name);
    EXPECT_EQ(got.color, expected.color);
    EXPECT_EQ(reader.entry(expected.id).color, expected.color);
    EXPECT_EQ(got.mesh.positions, expected.mesh.positions);
    EXPECT_EQ(got.mesh.normals, expected.mesh.normals);
    EXPECT_EQ(got.mesh.colors, expected.mesh.colors);
    EXPECT_EQ(got.mesh.indices, expected.mesh.indices);
    triangles += expected.mesh.triangle_count();
    bounds.extend(expected.bounds);
  }
  EXPECT_EQ(reader.triangle_count(), triangles);
  EXPECT_EQ(reader.info().bounds.min, bounds.min);
  EXPECT_EQ(reader.info().bounds.max, bounds.max);
}

TEST(SceneFile, CountsBytesRead) {
  test::TempDir dir;
  write_scene(dir.file("a.cwscene"), 3);
  SceneReader reader(dir.file("a.cwscene"));
  reader.read_object(1);
  reader.read_object(2);
  EXPECT_EQ(reader.bytes_read(), uint64_t{reader.entry(1).size} + reader.entry(2).size);
}

TEST(SceneFile, RejectsNonDenseIds) {
  test::TempDir dir;
  SceneWriter writer(dir.file("a.cwscene"));
  Random rng(1);
  EXPECT_THROW(writer.add(make_object(3, rng, false)), Error);
}

TEST(SceneFile, UnfinishedWriteLeavesNoFileAndKeepsTheOldOne) {
  test::TempDir dir;
  const std::string file = dir.file("a.cwscene");
  write_scene(file, 4, 1);
  const auto before = slurp(file);
  {
    SceneWriter writer(file);
    Random rng(2);
    writer.add(make_object(0, rng, false));
    // destroyed without finish(): as if the build was interrupted
  }
  EXPECT_EQ(slurp(file), before);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);
  {
    SceneWriter writer(dir.file("new.cwscene"));
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("new.cwscene")));
}

// Every single flipped byte and every truncation is either caught with an Error naming the
// file, or (for bytes no reader looks at, such as reserved fields) yields exactly the
// original objects: never a crash, never silently wrong geometry.
TEST(SceneFile, EveryFlippedByteIsCaughtOrHarmless) {
  test::TempDir dir;
  const std::string good = dir.file("good.cwscene"), bad = dir.file("bad.cwscene");
  auto objects = write_scene(good, 3);
  const auto bytes = slurp(good);
  int caught = 0, harmless = 0;
  for (size_t i = 0; i < bytes.size(); ++i) {
    auto damaged = bytes;
    damaged[i] ^= 0x5A;
    spit(bad, damaged);
    try {
      SceneReader reader(bad);
      for (const Object& o : objects) {
        Object got = reader.read_object(o.id);
        ASSERT_EQ(got.mesh.positions, o.mesh.positions) << "byte " << i;
        ASSERT_EQ(got.mesh.indices, o.mesh.indices) << "byte " << i;
      }
      ++harmless;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
      ++caught;
    }
  }
  EXPECT_GT(caught, static_cast<int>(bytes.size()) * 9 / 10);
  EXPECT_LE(harmless, 20);  // the header flags word and four frame padding words
}

TEST(SceneFile, EveryTruncationIsCaught) {
  test::TempDir dir;
  const std::string good = dir.file("good.cwscene"), bad = dir.file("bad.cwscene");
  write_scene(good, 3);
  const auto bytes = slurp(good);
  for (size_t n = 0; n < bytes.size(); n += 7) {
    spit(bad, std::vector<uint8_t>(bytes.begin(), bytes.begin() + static_cast<long>(n)));
    EXPECT_THROW(SceneReader{bad}, Error) << "truncated to " << n;
  }
}

// A crafted trailer whose offsets would wrap around 2^64 when added is refused before any
// allocation (it once asked for exabytes).
TEST(SceneFile, TrailerOffsetsThatWouldWrapAreRefused) {
  test::TempDir dir;
  const std::string file = dir.file("a.cwscene");
  write_scene(file, 2);
  auto bytes = slurp(file);
  const uint64_t end = bytes.size();
  for (uint64_t offset : {uint64_t{1} << 63, ~uint64_t{0} - (uint64_t{1} << 35)}) {
    const uint64_t size = (end - 24) - offset;  // wraps: offset + size == end - 24 modulo 2^64
    std::memcpy(bytes.data() + end - 24, &offset, 8);
    std::memcpy(bytes.data() + end - 16, &size, 8);
    spit(file, bytes);
    try {
      SceneReader r(file);
      FAIL() << "accepted a wrapped footer offset";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("footer position"), std::string::npos) << e.what();
    }
  }
}

// A damaged object record fails the build with one clear line, from any worker thread, and
// leaves no temporary file behind.
TEST(SceneFile, DamagedRecordFailsTheBuildCleanly) {
  test::TempDir dir;
  const std::string file = dir.file("a.cwscene");
  write_scene(file, 40);
  auto bytes = slurp(file);
  SceneReader reader(file);
  bytes[reader.entry(33).offset + 40] ^= 0xFF;  // inside object 33's payload
  spit(file, bytes);
  auto r = test::run_cellwalk("build " + file + " --threads 2 -o " + dir.file("w.cww"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("object 33: checksum mismatch"), std::string::npos) << r.output;
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);
}

TEST(SceneFile, ClearErrorsForWrongKindsOfInput) {
  test::TempDir dir;
  spit(dir.file("empty"), {});
  try {
    SceneReader r(dir.file("empty"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("too short"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SceneReader{dir.path().string()}, Error);
  EXPECT_THROW(SceneReader{dir.file("missing")}, Error);
  write_scene(dir.file("v.cwscene"), 1);
  auto bytes = slurp(dir.file("v.cwscene"));
  bytes[8] = 99;  // format version
  spit(dir.file("v.cwscene"), bytes);
  try {
    SceneReader r(dir.file("v.cwscene"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("version 99"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cellwalk
