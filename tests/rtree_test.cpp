// The disk R-tree of REVIEW (HDoV thesis §4.2.1): structure, Ang & Tan's split, searches against
// a brute-force oracle, exact page reads through the world file, damage.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/page_file.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/index/rtree.hpp"
#include "cellwalk/store/world.hpp"
#include "index/linear_split.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

std::vector<Aabb> random_boxes(size_t n, uint64_t seed, float extent = 1000.0f) {
  Random rng(seed);
  std::vector<Aabb> boxes;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 p(float(rng.uniform(0, extent)), float(rng.uniform(0, 30)), float(rng.uniform(0, extent)));
    const Vec3 s(float(rng.uniform(1, 25)), float(rng.uniform(3, 60)), float(rng.uniform(1, 25)));
    boxes.push_back({p, p + s});
  }
  return boxes;
}

Aabb random_cell(Random& rng, float extent = 1000.0f) {
  const Vec3 p(float(rng.uniform(-50, extent)), float(rng.uniform(-10, 20)), float(rng.uniform(-50, extent)));
  const Vec3 s(float(rng.uniform(10, 300)), float(rng.uniform(5, 100)), float(rng.uniform(10, 300)));
  return {p, p + s};
}

std::vector<uint32_t> brute_box(const std::vector<Aabb>& boxes, const Aabb& cell) {
  std::vector<uint32_t> out;
  for (size_t i = 0; i < boxes.size(); ++i)
    if (boxes[i].overlaps(cell)) out.push_back(uint32_t(i));
  return out;
}

std::vector<uint32_t> sorted(std::vector<uint32_t> v) {
  std::sort(v.begin(), v.end());
  return v;
}

RTreeCacheOptions no_cache() {
  RTreeCacheOptions o;
  o.policy = RTreeCacheOptions::Policy::kNone;
  return o;
}

TEST(RTree, InsertionKeepsFillBoundsAndFindsWhatBruteForceFinds) {
  const std::vector<Aabb> boxes = random_boxes(3000, 7);
  for (RTreeMethod method : {RTreeMethod::kLinearInsert, RTreeMethod::kStr}) {
    RTreeParams params;
    params.max_entries = 16;
    params.method = method;
    const RTreeBuild built = build_rtree(boxes, params, 4096);
    EXPECT_EQ(built.min_entries, 6u);
    EXPECT_GE(built.height(), 3u);
    for (size_t i = 1; i < built.nodes.size() && method == RTreeMethod::kLinearInsert; ++i)
      EXPECT_GE(built.nodes[i].entries.size(), built.min_entries) << "node " << i;
    const DiskRTree tree(encode_rtree_section(built));
    EXPECT_EQ(tree.check(), built.nodes.size());
    EXPECT_EQ(tree.height(), built.height());
    RTreeNodeCache cache(tree, no_cache());
    Random rng(3);
    for (int q = 0; q < 200; ++q) {
      const Aabb cell = random_cell(rng);
      std::vector<uint32_t> found;
      SearchCounters counters;
      box_search(cache, cell, found, counters);
      ASSERT_EQ(sorted(found), brute_box(boxes, cell)) << "query " << q;
      EXPECT_EQ(counters.node_reads, counters.node_visits);  // no cache: every visit is a page read
    }
  }
}

TEST(RTree, LinearSplitSeparatesTwoClustersAlongTheirAxis) {
  std::vector<RTreeEntry> entries;
  for (uint32_t i = 0; i < 9; ++i) {
    const float x = i < 5 ? float(i) : 100.0f + float(i);
    entries.push_back({Aabb{Vec3(x, 0, float(i % 3)), Vec3(x + 1, 5, float(i % 3) + 1)}, i});
  }
  auto [low, high] = linear_split(entries, 3);
  std::set<uint32_t> low_ids, high_ids;
  for (const RTreeEntry& e : low) low_ids.insert(e.ref);
  for (const RTreeEntry& e : high) high_ids.insert(e.ref);
  EXPECT_EQ(low_ids, (std::set<uint32_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(high_ids, (std::set<uint32_t>{5, 6, 7, 8}));
}

TEST(RTree, LinearSplitRefillsAnUnderfullGroup) {
  std::vector<RTreeEntry> entries;  // all but one hug the low border on every axis
  for (uint32_t i = 0; i < 8; ++i) entries.push_back({Aabb{Vec3(float(i) * 0.01f), Vec3(1.0f + float(i) * 0.01f)}, i});
  entries.push_back({Aabb{Vec3(50.0f), Vec3(51.0f)}, 8});
  auto [low, high] = linear_split(entries, 4);
  // Entry 8 alone is nearer the high border; the three low entries reaching furthest towards
  // it (largest max: 7, 6, 5) move over, the rest stay.
  std::set<uint32_t> low_ids, high_ids;
  for (const RTreeEntry& e : low) low_ids.insert(e.ref);
  for (const RTreeEntry& e : high) high_ids.insert(e.ref);
  EXPECT_EQ(low_ids, (std::set<uint32_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(high_ids, (std::set<uint32_t>{5, 6, 7, 8}));
}

TEST(RTree, CacheReadsEachPageOnceAndPinsTheRoot) {
  const std::vector<Aabb> boxes = random_boxes(2000, 11);
  RTreeParams params;
  params.max_entries = 20;
  const DiskRTree tree(encode_rtree_section(build_rtree(boxes, params, 4096)));
  RTreeCacheOptions options;
  options.bytes = 64 << 20;  // everything fits
  RTreeNodeCache cache(tree, options);
  const Aabb cell{Vec3(100, 0, 100), Vec3(400, 50, 300)};
  std::vector<uint32_t> a, b;
  SearchCounters first, second;
  box_search(cache, cell, a, first);
  box_search(cache, cell, b, second);
  EXPECT_EQ(a, b);
  EXPECT_EQ(first.node_reads, first.node_visits - 1);  // the root was read and pinned at start
  EXPECT_EQ(second.node_reads, 0u);
  // A cache of a few pages still answers correctly, reading more.
  options.bytes = 3 * 4096;
  for (RTreeCacheOptions::Policy p : {RTreeCacheOptions::Policy::kLru, RTreeCacheOptions::Policy::kDistancePriorityLru}) {
    options.policy = p;
    RTreeNodeCache c(tree, options);
    std::vector<uint32_t> found;
    SearchCounters counters;
    box_search(c, cell, found, counters);
    EXPECT_EQ(sorted(found), brute_box(boxes, cell));
    EXPECT_LE(c.resident_bytes(), options.bytes);
  }
  options.bytes = 100;
  EXPECT_THROW(RTreeNodeCache(tree, options), Error);
}

TEST(RTree, WorldSectionPageReadsAreExact) {
  test::TempDir dir;
  const std::string world_file = test::write_street_world(dir, 400);
  RTreeParams params;
  params.max_entries = 8;
  const RTreeBuild built = add_rtree_to_world(world_file, params);
  const World world(world_file);
  ASSERT_TRUE(world.file().has_section(kRTreeSection));
  const DiskRTree tree(world);
  EXPECT_EQ(tree.node_count(), built.nodes.size());
  EXPECT_EQ(tree.object_count(), 400u);
  EXPECT_EQ(tree.check(), built.nodes.size());
  std::vector<Aabb> boxes;
  for (ObjectId id = 0; id < world.object_count(); ++id) boxes.push_back(world.object(id).bounds);
  RTreeNodeCache cache(tree, no_cache());
  const Aabb cell{Vec3(100, 0, -20), Vec3(300, 10, 20)};
  world.file().pages().reset_counters();
  std::vector<uint32_t> found;
  SearchCounters counters;
  box_search(cache, cell, found, counters);
  EXPECT_EQ(sorted(found), brute_box(boxes, cell));
  EXPECT_GT(counters.node_reads, 2u);
  EXPECT_EQ(world.file().pages().counters().pages, counters.node_reads);  // one page per node, nothing else
}

TEST(RTree, DamageGivesOneClearError) {
  const RTreeBuild built = build_rtree(random_boxes(300, 5), RTreeParams{}, 4096);
  std::vector<uint8_t> section = encode_rtree_section(built);
  // An entry count beyond the page's capacity in the root's page.
  std::vector<uint8_t> bad = section;
  bad[4096 + 4] = 0xff;
  bad[4096 + 5] = 0xff;
  const DiskRTree tree(bad, "damaged");
  try {
    tree.read_node(0, tree.height() - 1);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("damaged node 0"), std::string::npos) << e.what();
  }
  bad = section;
  bad[0] = 9;  // version
  EXPECT_THROW(DiskRTree(bad, "damaged"), Error);
  bad = section;
  bad.resize(4096 + 100);  // cut inside the nodes
  EXPECT_THROW(DiskRTree(bad, "damaged"), Error);
  EXPECT_THROW(build_rtree({}, RTreeParams{1000, 0, RTreeMethod::kLinearInsert}, 4096), Error);
  EXPECT_THROW(build_rtree({}, RTreeParams{16, 9, RTreeMethod::kLinearInsert}, 4096), Error);
}

TEST(RTree, BuildWritesItAndInfoAndVerifyShowIt) {
  test::TempDir dir;
  const std::string scene = test::write_street_scene(dir, 200);
  const std::string world = dir.file("w.cww");
  auto r = test::run_cellwalk("build " + scene + " -o " + world + " --rtree-fanout 10");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cellwalk("info --json " + world);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["rtree"]["max_entries"], 10);
  EXPECT_GE(j["rtree"]["height"].get<int>(), 3);
  r = test::run_cellwalk("verify " + world);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("R-tree of"), std::string::npos) << r.output;
  r = test::run_cellwalk("build " + scene + " -o " + dir.file("x.cww") + " --rtree-fanout 1000");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("fan-out"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace cellwalk
