// The memory HDoV scene tree (HDoV thesis ch. 6): the k-d tree and its internal LODs (§5.6's
// size constraint), the VD invariants of §4 (DoV = Σ children's, a visible node has a visible
// child) under cell changes, and the traversals against brute-force oracles: CONV equals
// per-object frustum culling, VSC at η = 0 equals the naive visible list, PB never exceeds
// its budget. Then the strategies through the CLI on a world with stored DoVs.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/scene_tree/scene_tree.hpp"
#include "cellwalk/core/random.hpp"
#include "scene/shapes.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// Objects with real LOD chains (ellipsoids, tori, cylinders of a few hundred triangles) on both
// sides of a street along x, with a navigation graph down the street.
std::string write_test_world(const test::TempDir& dir, int count, uint64_t seed = 3) {
  Random rng(seed);
  std::vector<Object> objects;
  for (int i = 0; i < count; ++i) {
    Mesh mesh;
    switch (i % 3) {
      case 0: mesh = shapes::ellipsoid(Vec3(2.0f, 3.0f, 2.0f), 20, 12); break;
      case 1: mesh = shapes::torus(2.0f, 0.7f, 20, 10); break;
      default: mesh = shapes::cylinder(1.5f, 6.0f, 24); break;
    }
    const float side = i % 2 ? 1.0f : -1.0f;
    transform(mesh, shapes::place(Vec3(5.0f * float(i / 2), 0.5f, side * float(rng.uniform(5, 12))), float(rng.uniform(0, 90))));
    shapes::paint(mesh, rgba8(uint8_t(rng.integer(40, 255)), uint8_t(rng.integer(40, 255)), uint8_t(rng.integer(40, 255))));
    Object o;
    o.id = ObjectId(i);
    o.name = "o" + std::to_string(i);
    o.mesh = std::move(mesh);
    objects.push_back(std::move(o));
  }
  NavGraph nav;
  // Inside the objects' x range: view cells cover the world's box and the walk stays in them.
  nav.nodes = {Vec3(1, 1.7f, 0), Vec3(5.0f * float(count / 2) - 4, 1.7f, 0)};
  nav.edges = {{0, 1}};
  return test::write_world(dir, objects, nav, "hdov");
}

// A random visible set: each object visible with probability 1/2, DoVs spread over decades.
VisibleSet random_set(const World& world, Random& rng) {
  VisibleSet set;
  for (ObjectId id = 0; id < world.object_count(); ++id) {
    if (rng.uniform() < 0.5) continue;
    set.objects.push_back(id);
    set.dov.push_back(float(std::pow(10.0, rng.uniform(-6, -1))));
  }
  return set;
}

Camera random_camera(const SceneTree& tree, Random& rng) {
  Camera c;
  const Aabb& b = tree.node(0).box;
  c.position = Vec3(float(rng.uniform(b.min.x - 10, b.max.x + 10)), 1.7f, float(rng.uniform(b.min.z - 5, b.max.z + 5)));
  c.yaw_deg = float(rng.uniform(0, 360));
  c.far_plane = float(rng.uniform(20, 200));
  return c;
}

// Before the street's start, looking down it (+x): the whole street in view.
Camera street_camera() {
  Camera c;
  c.position = Vec3(-20, 1.7f, 0);
  c.yaw_deg = -90;
  return c;
}

// The oracle, the (cell, list-of-objects) method: the objects of `set` in the frustum.
std::set<ObjectId> naive_visible(const World& world, const VisibleSet& set, const Frustum& frustum) {
  std::set<ObjectId> naive;
  for (ObjectId id : set.objects)
    if (frustum.intersects(world.object(id).bounds)) naive.insert(id);
  return naive;
}

std::set<ObjectId> objects_of(const SceneTree& tree, const std::vector<TreeSelection>& selection) {
  std::set<ObjectId> out;
  for (const TreeSelection& s : selection) {
    EXPECT_TRUE(tree.node(s.node).is_leaf());
    out.insert(tree.node(s.node).object);
  }
  return out;
}

class HdovSceneTreeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    world_ = new World(write_test_world(*dir_, 40));
    tree_ = open_scene_tree(*world_, SceneTreeParams{}, dir_->file("hdov.scenetree")).release();
  }
  static void TearDownTestSuite() {
    delete tree_;
    delete world_;
    delete dir_;
  }
  static test::TempDir* dir_;
  static World* world_;
  static SceneTree* tree_;
};
test::TempDir* HdovSceneTreeTest::dir_ = nullptr;
World* HdovSceneTreeTest::world_ = nullptr;
SceneTree* HdovSceneTreeTest::tree_ = nullptr;

TEST_F(HdovSceneTreeTest, EveryObjectInOneLeafAndBoxesNest) {
  const SceneTree& tree = *tree_;
  ASSERT_EQ(tree.nodes().size(), 2 * world_->object_count() - 1);
  std::set<ObjectId> seen;
  for (NodeIndex n = 0; n < tree.nodes().size(); ++n) {
    const SceneTreeNode& node = tree.node(n);
    if (node.is_leaf()) {
      EXPECT_TRUE(seen.insert(node.object).second);
      EXPECT_EQ(tree.leaf_of(node.object), n);
      continue;
    }
    for (NodeIndex c : node.child) {
      EXPECT_GT(c, n);
      EXPECT_EQ(tree.node(c).parent, n);
      const Aabb& b = tree.node(c).box;
      EXPECT_TRUE(node.box.contains(b.min) && node.box.contains(b.max));
    }
    EXPECT_EQ(node.leaf_count, tree.node(node.child[0]).leaf_count + tree.node(node.child[1]).leaf_count);
  }
  EXPECT_EQ(seen.size(), world_->object_count());
}

TEST_F(HdovSceneTreeTest, InternalLodIsSmallerThanChildrenCoarsest) {
  const SceneTree& tree = *tree_;
  size_t with_lods = 0;
  for (NodeIndex n = 0; n < tree.nodes().size(); ++n) {
    const SceneTreeNode& node = tree.node(n);
    if (node.is_leaf() || node.level_count == 0) continue;
    ++with_lods;
    // A child without LODs of its own stands for what it aggregates: its children's coarsest.
    std::function<uint64_t(NodeIndex)> coarsest = [&](NodeIndex c) -> uint64_t {
      const SceneTreeNode& k = tree.node(c);
      if (k.level_count > 0) return tree.triangles(c, k.level_count - 1);
      return coarsest(k.child[0]) + coarsest(k.child[1]);
    };
    EXPECT_LT(tree.triangles(n, 0), coarsest(node.child[0]) + coarsest(node.child[1])) << "node " << n;
    for (uint32_t l = 1; l < node.level_count; ++l) EXPECT_LT(tree.triangles(n, l), tree.triangles(n, l - 1));
    const Mesh m = tree.read_aggregate(n, node.level_count - 1);
    EXPECT_EQ(m.triangle_count(), tree.triangles(n, node.level_count - 1));
    EXPECT_EQ(m.colors.size(), m.vertex_count());
  }
  EXPECT_GT(with_lods, tree.nodes().size() / 4);
}

TEST_F(HdovSceneTreeTest, VdSumsChildrenAndSurvivesCellChanges) {
  const SceneTree& tree = *tree_;
  Random rng(7);
  SceneTreeVisibility vd(tree);
  for (int round = 0; round < 5; ++round) {
    const VisibleSet set = random_set(*world_, rng);
    vd.assign(set);
    SceneTreeVisibility fresh(tree);  // no history: what a cell change must leave behind
    fresh.assign(set);
    for (NodeIndex n = 0; n < tree.nodes().size(); ++n) {
      const SceneTreeNode& node = tree.node(n);
      EXPECT_EQ(vd[n].dov, fresh[n].dov);
      EXPECT_EQ(vd[n].nvo, fresh[n].nvo);
      if (node.is_leaf()) continue;
      const VisibilityDatum& a = vd[node.child[0]];
      const VisibilityDatum& b = vd[node.child[1]];
      EXPECT_EQ(vd[n].dov, a.dov + b.dov) << "node " << n;  // exact: computed so
      EXPECT_EQ(vd[n].nvo, a.nvo + b.nvo);
      if (vd[n].dov > 0) {
        EXPECT_TRUE(a.dov > 0 || b.dov > 0) << "visible node " << n << " has no visible child";
      }
    }
    EXPECT_EQ(vd[0].nvo, set.objects.size());
  }
  VisibleSet no_dov;
  no_dov.objects = {0};
  EXPECT_THROW(vd.assign(no_dov), Error);
}

TEST_F(HdovSceneTreeTest, ConvEqualsPerObjectFrustumCulling) {
  Random rng(11);
  std::vector<TreeSelection> out;
  TraversalStats stats;
  for (int i = 0; i < 50; ++i) {
    const Camera camera = random_camera(*tree_, rng);
    const Frustum frustum(camera);
    conv_traverse(*tree_, frustum, out, stats);
    std::set<ObjectId> oracle;
    for (ObjectId id = 0; id < world_->object_count(); ++id)
      if (frustum.intersects(world_->object(id).bounds)) oracle.insert(id);
    EXPECT_EQ(objects_of(*tree_, out), oracle);
    for (const TreeSelection& s : out) EXPECT_EQ(s.level, 0u);
    EXPECT_LE(stats.nodes_visited, tree_->nodes().size());
  }
}

TEST_F(HdovSceneTreeTest, VscAtEtaZeroEqualsNaiveVisibleList) {
  Random rng(13);
  SceneTreeVisibility vd(*tree_);
  std::vector<TreeSelection> out;
  TraversalStats stats;
  for (int i = 0; i < 30; ++i) {
    const VisibleSet set = random_set(*world_, rng);
    vd.assign(set);
    const Camera camera = random_camera(*tree_, rng);
    const Frustum frustum(camera);
    const std::set<ObjectId> naive = naive_visible(*world_, set, frustum);
    vsc_traverse(*tree_, vd, frustum, {.eta = 0.0, .dov_leaf_levels = false}, out, stats);
    EXPECT_EQ(objects_of(*tree_, out), naive);
    for (const TreeSelection& s : out) EXPECT_EQ(s.level, 0u);  // full detail
    vsc_traverse(*tree_, vd, frustum, {.eta = 0.0}, out, stats);  // eq. 5.6 levels: same objects
    EXPECT_EQ(objects_of(*tree_, out), naive);
  }
}

TEST_F(HdovSceneTreeTest, VscLargerEtaStopsHigherInTheTree) {
  Random rng(17);
  SceneTreeVisibility vd(*tree_);
  vd.assign(random_set(*world_, rng));
  const Frustum frustum(street_camera());
  std::vector<TreeSelection> out;
  TraversalStats previous, stats;
  vsc_traverse(*tree_, vd, frustum, {.eta = 0.0}, out, previous);
  for (double eta : {1e-4, 1e-3, 1e-2, 1.0}) {
    vsc_traverse(*tree_, vd, frustum, {.eta = eta}, out, stats);
    // Stopping is monotone in η, so the search only gets shallower (triangles need not fall:
    // a stopped node's LOD also stands for children outside the frustum).
    EXPECT_LE(stats.nodes_visited, previous.nodes_visited) << eta;
    previous = stats;
  }
  EXPECT_GT(stats.active_internal, 0u);
  EXPECT_EQ(out.size(), 1u);  // η = 1 ≥ the root's DoV: the whole street as one LOD
}

TEST_F(HdovSceneTreeTest, PbNeverExceedsItsBudget) {
  Random rng(19);
  SceneTreeVisibility vd(*tree_);
  std::vector<TreeSelection> out;
  TraversalStats stats;
  for (int i = 0; i < 20; ++i) {
    vd.assign(random_set(*world_, rng));
    const Frustum frustum(random_camera(*tree_, rng));
    for (uint64_t budget : {1ull, 30ull, 200ull, 1000ull, 5000ull, 100000ull}) {
      for (bool dov_levels : {true, false}) {
        pb_traverse(*tree_, vd, frustum, {.budget = budget, .dov_levels = dov_levels}, out, stats);
        EXPECT_LE(stats.triangles, budget);
      }
      uint64_t sum = 0;
      for (const TreeSelection& s : out) sum += tree_->triangles(s.node, s.level);
      EXPECT_EQ(sum, stats.triangles);
    }
  }
  // A budget nothing binds draws every visible object in the frustum (at λ's level).
  const VisibleSet set = random_set(*world_, rng);
  vd.assign(set);
  const Frustum frustum(random_camera(*tree_, rng));
  pb_traverse(*tree_, vd, frustum, {.budget = 1ull << 40}, out, stats);
  const std::set<ObjectId> naive = naive_visible(*world_, set, frustum);
  EXPECT_EQ(objects_of(*tree_, out), naive);
  // Without λ, PB(∞) is VSC(0) at full detail ("degrades to CONV" on the visible set).
  pb_traverse(*tree_, vd, frustum, {.budget = 1ull << 40, .dov_levels = false}, out, stats);
  EXPECT_EQ(objects_of(*tree_, out), naive);
  for (const TreeSelection& s : out) EXPECT_EQ(s.level, 0u);
}

TEST_F(HdovSceneTreeTest, PbTightBudgetFallsBackToInternalLods) {
  Random rng(23);
  SceneTreeVisibility vd(*tree_);
  vd.assign(random_set(*world_, rng));
  std::vector<TreeSelection> out;
  TraversalStats stats;
  pb_traverse(*tree_, vd, Frustum(street_camera()), {.budget = 300}, out, stats);
  EXPECT_GT(stats.active_internal, 0u);
  EXPECT_GT(stats.triangles, 0u);
  EXPECT_LE(stats.triangles, 300u);
}

TEST(HdovSceneTreeFile, DamageIsReportedAndOtherWorldsRebuild) {
  test::TempDir dir;
  const World world(write_test_world(dir, 12, 5));
  const std::string file = dir.file("t.scenetree");
  open_scene_tree(world, SceneTreeParams{}, file);
  // Other parameters: rebuilt, not refused.
  SceneTreeParams one_level;
  one_level.lods.levels = 1;
  const auto rebuilt = open_scene_tree(world, one_level, file);
  EXPECT_EQ(rebuilt->params().lods.levels, 1u);
  // A tree file of another world is refused by name.
  test::TempDir other_dir;
  const World other(write_test_world(other_dir, 12, 6));
  try {
    SceneTree t(other, file);
    FAIL() << "accepted another world's tree";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("another world"), std::string::npos) << e.what();
  }
  // A flipped byte in a page: one error naming the file, never a crash.
  uint64_t offset = 0;
  {
    const WorldFile probe(file, {});
    offset = probe.section("kd-nodes").first_page * probe.page_size() + 10;
  }
  std::vector<uint8_t> bytes = test::slurp(file);
  bytes.at(offset) ^= 0x5a;
  test::spit(file, bytes);
  try {
    SceneTree t(world, file);
    FAIL() << "accepted a damaged tree file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
  }
}

// The strategies end to end: DoVs precomputed by `cellwalk pvs`, then walk and compare.
TEST(HdovSceneTreeStrategies, WalkAndCompareThroughTheCli) {
  test::TempDir dir;
  const std::string world = write_test_world(dir, 24, 9);
  const std::string path = dir.file("p.path");
  auto r = test::run_cellwalk("path " + world + " --frames 12 -o " + path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Without stored DoVs hdov-vsc says what to run; conv needs none.
  r = test::run_cellwalk("walk " + world + " --path " + path + " --strategy hdov-vsc --width 64 --height 48 -o " +
                         dir.file("w0"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("cellwalk pvs"), std::string::npos) << r.output;
  r = test::run_cellwalk("pvs " + world + " --engine dov --cells grid:20 --dov-resolution 16 --points 4 --rays 256");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string strategy : {"conv", "hdov-vsc", "hdov-pb"}) {
    r = test::run_cellwalk("walk " + world + " --path " + path + " --strategy " + strategy +
                           " --budget 8 --polygon-budget 2000 --eta 0.001 --width 64 --height 48 --json -o " +
                           dir.file(strategy));
    ASSERT_EQ(r.exit_code, 0) << strategy << ": " << r.output;
    const auto j = test::only_run(r);
    EXPECT_LE(j["peak_resident_bytes"].get<uint64_t>(), 8ull << 20) << strategy;
  }
  // CONV draws what brute draws: no pixel differs from ground truth.
  r = test::run_cellwalk("compare " + world + " --path " + path + " --strategy conv --every 4 --width 64 --height 48 --json -o " +
                         dir.file("cmp"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = test::only_run(r);
  EXPECT_EQ(j["mean_differing_fraction"].get<double>(), 0.0);
}

}  // namespace
}  // namespace cellwalk
