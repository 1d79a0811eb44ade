#include "cellwalk/store/world.hpp"

#include <gtest/gtest.h>

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

// A flipped byte anywhere in the header's fields or in a data page is caught; the only bytes no
// checksum covers are padding never read: the header page's tail and the two tables' last
// pages' tails.
TEST_F(BuiltWorld, EveryFlippedByteIsCaughtOrHarmless) {
  const auto bytes = slurp(world_);
  const std::string bad = dir_.file("bad.cww");
  uint64_t data_end = 0;
  const World clean(world_);
  for (const SectionInfo& s : clean.file().sections())
    data_end = std::max(data_end, (s.first_page + s.page_count(4096)) * 4096);
  int caught = 0;
  for (size_t i = 0; i < bytes.size(); i += (i < 128 ? 1 : 31)) {
    auto damaged = bytes;
    damaged[i] ^= 0x21;
    spit(bad, damaged);
    try {
      World w(bad);
      w.file().verify();
      for (ObjectId id = 0; id < w.object_count(); ++id) w.decode_level(id, 0, w.read_level(id, 0));
      const bool padding = (i >= 96 && i < 4096) || i >= data_end;  // the header has 96 bytes
      EXPECT_TRUE(padding) << "flipped byte " << i << " went unnoticed";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
      ++caught;
    }
  }
  EXPECT_GT(caught, 128);
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
  const std::string command = "bash -c \"trap '' XFSZ; ulimit -f 8; exec " + std::string(CELLWALK_BINARY) +
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
