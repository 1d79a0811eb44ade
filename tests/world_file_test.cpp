#include "cellwalk/store/world.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using test::slurp;
using test::spit;

TEST(WorldFile, SectionsRoundTripAcrossPageBoundaries) {
  test::TempDir dir;
  const std::string file = dir.file("w.cww");
  std::vector<uint8_t> a(10000), b(1), c(4096);
  for (size_t i = 0; i < a.size(); ++i) a[i] = static_cast<uint8_t>(i * 7);
  c.assign(4096, 0xAB);
  {
    WorldWriter w(file, 4096);
    w.begin_section("a");
    w.write(std::span(a).first(3000));
    EXPECT_EQ(w.section_offset(), 3000u);
    w.write(std::span(a).subspan(3000));
    w.end_section();
    w.begin_section("b");
    w.write(b);
    w.end_section();
    w.begin_section("c");
    w.write(c);
    w.end_section();
    w.finish();
  }
  WorldFile f(file, {});
  EXPECT_EQ(f.page_size(), 4096u);
  EXPECT_EQ(std::filesystem::file_size(file), f.page_count() * 4096);
  EXPECT_EQ(f.read_all("a"), a);
  EXPECT_EQ(f.read_all("b"), b);
  EXPECT_EQ(f.read_all("c"), c);
  auto part = f.read(f.section("a"), 4090, 20);  // straddles pages 1 and 2 of the section
  EXPECT_EQ(part, std::vector<uint8_t>(a.begin() + 4090, a.begin() + 4110));
  EXPECT_THROW(f.read(f.section("b"), 0, 2), Error);
  EXPECT_THROW(f.section("missing"), Error);
  EXPECT_EQ(f.verify(), f.section("c").first_page + 1);
  EXPECT_TRUE(is_world_file(file));
}

// Issue 13, item 12: every byte of a world file is checked by `verify` (docs/format.md, "What
// is checked"): the header's fields by its hash, the data pages by their XXH32s, the tables by
// their hashes, and everything else (the header page after its fields, the tables' last-page
// tails) must be zero. So a flip of any one bit of the file, of any of its bytes, is caught,
// by opening the file or by verify(), with a message naming the file. Flipped in place in a
// copy and put back, so the test stays quick.
TEST(WorldFile, EveryFlippedByteIsCaught) {
  test::TempDir dir;
  const std::string world = test::write_street_world(dir, 3);
  const std::string bad = dir.file("bad.cww");
  std::filesystem::copy_file(world, bad);
  const std::vector<uint8_t> bytes = slurp(bad);
  {
    const WorldFile clean(bad, {});
    ASSERT_EQ(clean.verify(), clean.page_count() - 2);  // every page but the two tables'
    ASSERT_LE(bytes.size(), 20u * 4096) << "a larger world makes this test slow";
  }
  const int fd = ::open(bad.c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  const auto put = [fd](size_t at, uint8_t value) { ASSERT_EQ(::pwrite(fd, &value, 1, off_t(at)), 1); };
  size_t missed = 0;
  for (size_t i = 0; i < bytes.size(); ++i) {
    put(i, uint8_t(bytes[i] ^ (1u << (i % 8))));
    try {
      WorldFile(bad, {}).verify();
      if (++missed <= 10) ADD_FAILURE() << "a flipped bit in byte " << i << " went unnoticed";
    } catch (const Error& e) {
      if (std::string(e.what()).rfind(bad + "@", 0) != 0) ADD_FAILURE() << "byte " << i << ": " << e.what();
    }
    put(i, bytes[i]);
  }
  ::close(fd);
  EXPECT_EQ(missed, 0u) << "of " << bytes.size() << " bytes";
  EXPECT_EQ(slurp(bad), bytes);
}

// The unchecked padding of the header page and of the tables' last pages is named where it is.
TEST(WorldFile, NonZeroPaddingIsNamedWithItsOffset) {
  test::TempDir dir;
  const std::string world = test::write_street_world(dir, 3);
  const std::vector<uint8_t> bytes = slurp(world);
  const uint64_t pages = bytes.size() / 4096;
  const std::pair<uint64_t, const char*> cases[] = {{100, "header page: padding byte is not zero"},
                                                    {4095, "header page: padding byte is not zero"},
                                                    {(pages - 1) * 4096 - 1, "page checksum table: padding byte"},
                                                    {bytes.size() - 1, "section table: padding byte"}};
  for (const auto& [at, expect] : cases) {
    std::vector<uint8_t> damaged = bytes;
    damaged[at] = 0x40;
    spit(world, damaged);
    try {
      WorldFile f(world, {});
      ADD_FAILURE() << "byte " << at << " went unnoticed";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(world + "@" + std::to_string(at) + ": " + expect, 0), 0u) << e.what();
    }
  }
}

class BuiltWorld : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = test::write_street_scene(dir_, 12);
    world_ = dir_.file("w.cww");
    report_ = build_world(scene_, world_, BuildParams{});
  }
  test::TempDir dir_;
  std::string scene_, world_;
  BuildReport report_;
};

TEST_F(BuiltWorld, HoldsEveryObjectWithItsLevels) {
  World world(world_);
  SceneReader scene(scene_);
  ASSERT_EQ(world.object_count(), scene.object_count());
  EXPECT_EQ(world.triangle_count(), scene.triangle_count());
  EXPECT_EQ(report_.triangles, scene.triangle_count());
  EXPECT_EQ(world.info().nav.edges.size(), scene.info().nav.edges.size());
  for (ObjectId id = 0; id < scene.object_count(); ++id) {
    const Object o = scene.read_object(id);
    EXPECT_EQ(world.object(id).color, o.color);
    EXPECT_EQ(world.object(id).bounds.min, o.bounds.min);
    Mesh level0 = world.decode_level(id, 0, world.read_level(id, 0));
    EXPECT_EQ(level0.triangle_count(), o.mesh.triangle_count());
    // Quantised positions stay within the codec's bound of the originals' box.
    Aabb box = bounds_of(level0);
    EXPECT_LT(glm::distance(box.min, o.bounds.min), 1e-3f);
    EXPECT_LT(glm::distance(box.max, o.bounds.max), 1e-3f);
  }
}

TEST_F(BuiltWorld, DamagedPageNamesSectionAndOffset) {
  auto bytes = slurp(world_);
  World clean(world_);
  const SectionInfo& geometry = clean.file().section("geometry");
  ASSERT_GT(geometry.bytes, 1000u);
  bytes[geometry.first_page * 4096 + 1000] ^= 1;
  spit(world_, bytes);
  World w(world_);  // header and tables are intact
  try {
    w.file().verify();
    FAIL() << "verify passed a flipped byte";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("section geometry@0: page checksum mismatch"), std::string::npos) << e.what();
  }
  auto r = test::run_cellwalk("verify " + world_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("section geometry@0"), std::string::npos) << r.output;
}

TEST_F(BuiltWorld, TruncatedOrWrongVersionIsRejectedClearly) {
  auto bytes = slurp(world_);
  const std::string bad = dir_.file("bad.cww");
  for (size_t n : {size_t(0), size_t(100), size_t(4096), bytes.size() / 2, bytes.size() - 1}) {
    spit(bad, std::vector<uint8_t>(bytes.begin(), bytes.begin() + static_cast<long>(n)));
    EXPECT_THROW(World{bad}, Error) << n;
  }
  auto versioned = bytes;
  versioned[8] = 7;
  spit(bad, versioned);
  try {
    World w(bad);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("version 7"), std::string::npos) << e.what();
  }
}

TEST_F(BuiltWorld, FailedBuildLeavesThePreviousWorldIntact) {
  const auto before = slurp(world_);
  // A file-size limit makes writes fail as a full disk would (SIGXFSZ ignored: write returns EFBIG).
  const std::string command = "bash -c \"trap '' XFSZ; ulimit -f 8; exec " + test::cellwalk_binary() +
                              " build " + scene_ + " -o " + world_ + "\" 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[1024];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  const int status = pclose(pipe);
  EXPECT_NE(status, 0);
  EXPECT_NE(output.find(world_ + ": write failed"), std::string::npos) << output;
  EXPECT_EQ(slurp(world_), before);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_.path()), {}), 2);  // scene + world
}

// The hard budget: walking with a geometry budget far below the world's size never holds
// more than the budget, and still draws every object.
TEST_F(BuiltWorld, StoreNeverExceedsItsBudget) {
  World world(world_);
  uint64_t largest = 0, total = 0;
  for (ObjectId id = 0; id < world.object_count(); ++id) {
    Mesh m = world.decode_level(id, 0, world.read_level(id, 0));
    largest = std::max<uint64_t>(largest, sizeof(Mesh) + m.byte_size());
    total += sizeof(Mesh) + m.byte_size();
  }
  const uint64_t budget = world.resident_bytes() + 2 * largest;
  ASSERT_LT(budget, world.resident_bytes() + total / 3);
  GeometryStore store(world, budget);
  Random rng(4);
  FetchStats stats;
  for (int i = 0; i < 500; ++i) {
    const ObjectId id = static_cast<ObjectId>(rng.integer(0, static_cast<int64_t>(world.object_count()) - 1));
    auto mesh = store.get(id, 0, EntryMeta{}, stats);
    ASSERT_EQ(mesh->triangle_count(), world.lod(id, 0).triangles);
    ASSERT_LE(store.resident_bytes(), budget);
  }
  EXPECT_LE(store.peak_resident_bytes(), budget);
  EXPECT_LE(store.budget().peak(), budget);
  EXPECT_GT(stats.cache_misses, world.object_count());  // it had to evict and reload
  EXPECT_THROW(GeometryStore(world, world.resident_bytes() / 2), Error);
}

TEST_F(BuiltWorld, ConcurrentReadersSeeTheSameBytes) {
  World world(world_);
  std::vector<std::vector<uint8_t>> expected;
  for (ObjectId id = 0; id < world.object_count(); ++id) expected.push_back(world.read_level(id, 0));
  std::atomic<int> mismatches{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      Random rng(static_cast<uint64_t>(t));
      for (int i = 0; i < 300; ++i) {
        const ObjectId id = static_cast<ObjectId>(rng.integer(0, static_cast<int64_t>(world.object_count()) - 1));
        if (world.read_level(id, 0) != expected[id]) ++mismatches;
        world.decode_level(id, 0, expected[id]);
      }
    });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(mismatches.load(), 0);
}

TEST_F(BuiltWorld, InfoAndVerifyCommands) {
  auto r = test::run_cellwalk("info --json " + world_);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"objects\": 12"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"geometry\""), std::string::npos);
  r = test::run_cellwalk("verify " + world_);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("is intact"), std::string::npos);
}

}  // namespace
}  // namespace cellwalk
