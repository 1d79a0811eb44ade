// vLOD (seed 001): the per-cell level rule (§2.2), visibility on the levels drawn (§4), and the
// strategy end to end: a walk that misses no visible object and draws coarser levels than brute.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <numeric>

#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/precompute/conservative_visibility.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "precompute/embree_scene.hpp"
#include "precompute/pvs_builder.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/scene_tree/scene_tree.hpp"
#include "cellwalk/systems/vlod/vlod_strategy.hpp"
#include "cellwalk/visibility/cell_lod.hpp"
#include "cellwalk/visibility/disk_order.hpp"
#include "cellwalk/visibility/stored_vlod.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using visibility::CellLodRule;


// A small city with real LOD chains, built once for the suite.
class VlodCity : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    inputs_ = new test::SharedInputs(
        "vlod-city", {"generate city --objects 60 --seed 5 -o {dir}/city.cwscene", "build {dir}/city.cwscene -o {dir}/city.cww"});
    world_ = inputs_->file("city.cww");
  }
  static void TearDownTestSuite() { delete inputs_; }
  static inline test::SharedInputs* inputs_ = nullptr;
  static inline std::string world_;
  const test::TempDir out_;  // this test's outputs
};

// Against the oracle of the definition: the level chosen meets the bound over the cell, the
// next coarser one does not, and an object the cell touches is drawn at level 0.
TEST_F(VlodCity, CellLevelIsTheCoarsestWithinTheBound) {
  const World world(world_);
  CellLodRule rule;
  rule.lens.viewport_height_px = 480;
  Random rng(7);
  const Aabb bounds = world.info().bounds;
  uint64_t coarser = 0, touching = 0;
  for (int i = 0; i < 200; ++i) {
    const Vec3 corner(float(rng.uniform(bounds.min.x, bounds.max.x)), 1.5f, float(rng.uniform(bounds.min.z, bounds.max.z)));
    const Aabb cell{corner, corner + Vec3(4.0f, 0.5f, 4.0f)};
    for (ObjectId id = 0; id < world.object_count(); ++id) {
      const uint32_t level = visibility::cell_level(world, id, cell, rule);
      const ObjectRecord& o = world.object(id);
      ASSERT_LT(level, o.lod_count);
      const float pixels = cell_pixels_per_unit(cell, o.bounds, rule.lens);
      if (o.bounds.overlaps(cell)) {
        EXPECT_EQ(level, 0u);
        ++touching;
        continue;
      }
      EXPECT_LT(world.lod(id, level).error * pixels, rule.pixel_error);
      if (level + 1 < o.lod_count) {
        EXPECT_GE(world.lod(id, level + 1).error * pixels, rule.pixel_error);
      }
      coarser += level > 0;
    }
  }
  EXPECT_GT(coarser, 0u) << "no object was ever drawn coarser: the test shows nothing";
  EXPECT_GT(touching + coarser, 0u);
}

TEST(CellLodRule, ReadsBackWhatItWritesAndRefusesTheRest) {
  CellLodRule rule;
  rule.pixel_error = 0.5f;
  rule.lens = Lens{0.9f, 1.5f, 720.0f};
  rule.formula = CellBoundFormula::kFaithful;
  const CellLodRule back = visibility::parse_cell_lod_rule(visibility::to_string(rule), "test");
  EXPECT_FLOAT_EQ(back.pixel_error, 0.5f);
  EXPECT_NEAR(back.lens.fov_y_rad, 0.9f, 1e-4f);
  EXPECT_FLOAT_EQ(back.lens.aspect, 1.5f);
  EXPECT_FLOAT_EQ(back.lens.viewport_height_px, 720.0f);
  EXPECT_EQ(back.formula, CellBoundFormula::kFaithful);
  for (const char* bad : {"", "px=1", "px=-1,h=480,fov=60,aspect=1,formula=corrected",
                          "px=1,h=480,fov=60,aspect=1,formula=other", "px=1,h=480,fov=60,aspect=1,formula=corrected,x=2"})
    EXPECT_THROW(visibility::parse_cell_lod_rule(bad, "test"), Error) << bad;
}

// A smaller or narrower image magnifies less and keeps the bound; a taller or wider one does not.
TEST(CellLodRule, CoversOnlyImagesThatMagnifyNoMore) {
  CellLodRule rule;
  rule.lens = Lens{1.0471976f, 4.0f / 3.0f, 480.0f};
  EXPECT_TRUE(visibility::rule_covers(rule, rule.lens));
  EXPECT_TRUE(visibility::rule_covers(rule, Lens{1.0471976f, 4.0f / 3.0f, 240.0f}));
  EXPECT_FALSE(visibility::rule_covers(rule, Lens{1.0471976f, 4.0f / 3.0f, 960.0f}));
  EXPECT_FALSE(visibility::rule_covers(rule, Lens{1.0471976f, 3.0f, 480.0f}));
}

// §4 through occluder_margin: a wall 3 m thick still hides the box behind it when its levels
// may lie 1 m off, and hides nothing once they may lie 2 m off (the eroded box is empty).
TEST(VlodVisibility, OccludersAreErodedByTheErrorOfTheLevelDrawn) {
  test::TempDir dir;
  std::vector<Object> objects;
  for (const Aabb& b : {Aabb{Vec3(5, 0, -10), Vec3(8, 10, 10)}, Aabb{Vec3(12, 1, -0.5f), Vec3(13, 2, 0.5f)}}) {
    Object o;
    o.id = ObjectId(objects.size());
    o.name = "box" + std::to_string(o.id);
    o.mesh = test::box_mesh(b);
    o.bounds = b;
    objects.push_back(o);
  }
  const World world(test::write_world(dir, objects, NavGraph{}));
  const ViewCell cell{0, Aabb{Vec3(-1, 1, -1), Vec3(1, 3, 1)}, 0, false};
  auto visible = [&](float margin) {
    ConservativeParams params;
    params.occluder_margin = [margin](const Aabb&, ObjectId) { return margin; };
    return make_conservative_engine(world, params)->compute(cell).objects;
  };
  EXPECT_EQ(visible(0.0f), std::vector<ObjectId>{0});
  EXPECT_EQ(visible(1.0f), std::vector<ObjectId>{0});
  EXPECT_EQ(visible(2.0f), (std::vector<ObjectId>{0, 1}));
}

// Eroding occluders can only reveal: on a street, every set with margins holds the set without.
TEST(VlodVisibility, MarginsOnlyAddToTheSet) {
  test::TempDir dir;
  const World world(test::write_street_world(dir, 16));
  Random rng(3);
  uint64_t hidden_somewhere = 0;
  for (int i = 0; i < 8; ++i) {
    const float x = float(rng.uniform(-4, 40));
    const ViewCell cell{0, Aabb{Vec3(x, 1.45f, -1.0f), Vec3(x + 2.0f, 1.95f, 1.0f)}, 0, false};
    const std::vector<ObjectId> plain = make_conservative_engine(world, {})->compute(cell).objects;
    ConservativeParams eroded;
    eroded.occluder_margin = [&](const Aabb&, ObjectId id) { return float(id % 3) * 0.4f; };
    const std::vector<ObjectId> more = make_conservative_engine(world, eroded)->compute(cell).objects;
    EXPECT_TRUE(std::includes(more.begin(), more.end(), plain.begin(), plain.end())) << "cell at x = " << x;
    hidden_somewhere += world.object_count() - plain.size();
  }
  EXPECT_GT(hidden_somewhere, 0u) << "nothing was ever hidden: the test shows nothing";
}

// End to end: `pvs --engine vlod`, then compare against ground truth: no visible object missed,
// and the vLOD draws fewer triangles than brute on the same path.
TEST_F(VlodCity, WalkMissesNoVisibleObjectAndDrawsCoarserLevels) {
  // pvs writes its sets into the world: a copy of the suite's.
  const std::string world = out_.file("city.cww"), path = out_.file("p.path");
  std::filesystem::copy_file(world_, world);
  auto r = test::run_cellwalk("path " + world + " --frames 24 --seed 3 -o " + path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Without vLOD sets the strategy says what to run.
  r = test::run_cellwalk("walk " + world + " --path " + path + " --strategy vlod --width 96 --height 72 -o " + out_.file("w0"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--engine vlod"), std::string::npos) << r.output;
  // The world keeps another run's DoVs beside its vLODs: hdov-vsc walks it after vlod's pvs.
  r = test::run_cellwalk("pvs " + world + " --engine dov --cells grid:30 --dov-resolution 16 --points 4 --rays 256");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cellwalk("pvs " + world + " --engine vlod --cells grid:40 --refine 1 --lod-height 72 --lod-aspect 1.3333334");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cellwalk("walk " + world + " --path " + path + " --strategy hdov-vsc --width 96 --height 72 -o " + out_.file("w-dov"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cellwalk("compare " + world + " --path " + path + " --strategy vlod --every 2 --width 96 --height 72 --json -o " +
                         out_.file("cmp"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto fidelity = test::only_run(r);
  ASSERT_TRUE(fidelity.is_object()) << r.output;
  EXPECT_GT(fidelity["visible_objects"].get<uint64_t>(), 0u);
  EXPECT_EQ(fidelity["missed_objects"].get<uint64_t>(), 0u) << r.output;
  uint64_t triangles[2] = {0, 0};
  int k = 0;
  for (const std::string strategy : {"brute", "vlod"}) {
    r = test::run_cellwalk("walk " + world + " --path " + path + " --strategy " + strategy +
                           " --budget 48 --width 96 --height 72 --json -o " + out_.file("walk-" + strategy));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto j = test::only_run(r);
    ASSERT_TRUE(j.is_object()) << r.output;
    EXPECT_LE(j["peak_resident_bytes"].get<uint64_t>(), j["strategy_budget_bytes"].get<uint64_t>()) << strategy;
    triangles[k++] = j["total_triangles"].get<uint64_t>();
  }
  EXPECT_LT(triangles[1], triangles[0]);
  // An image taller than the levels were chosen for would break their bound: refused.
  r = test::run_cellwalk("walk " + world + " --path " + path + " --strategy vlod --width 640 --height 480 -o " + out_.file("w1"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--lod-height"), std::string::npos) << r.output;
}

// §2.1: the octree refines a cell while its vLOD has more triangles than the threshold (unless
// the futility rule stops it): above every root cell's count nothing is refined; below the
// largest some root is, and every leaf is no larger than its root.
TEST_F(VlodCity, OctreeRefinesByTheTrianglesOfTheVlod) {
  const World world(world_);
  EngineOptions options;
  options.refine_levels = 1;
  options.lod_rule.lens.viewport_height_px = 72;
  const auto engine = make_engine("vlod", world, options);
  const visibility::EmbreeScene scene(world);
  const CellSetSize measure = visibility::drawn_triangles(*engine, world, options.lod_rule);
  const auto roots = visibility::make_partition("grid:80", world, scene);
  uint64_t largest = 0;
  for (CellId c = 0; c < roots->cell_count(); ++c) largest = std::max(largest, measure(roots->cell(c).box));
  ASSERT_GT(largest, 0u);
  const auto flat = visibility::make_partition("octree:80:" + std::to_string(largest) + ":3", world, scene, measure);
  EXPECT_EQ(flat->cell_count(), roots->cell_count());
  const auto refined = visibility::make_partition("octree:80:" + std::to_string(largest / 4) + ":3", world, scene, measure);
  EXPECT_GT(refined->cell_count(), roots->cell_count());
  uint32_t deepest = 0;
  for (CellId c = 0; c < refined->cell_count(); ++c) {
    const ViewCell& cell = refined->cell(c);
    deepest = std::max(deepest, cell.depth);
    EXPECT_LE(cell.depth, 3u);
    EXPECT_LE(cell.box.size().x, 80.0f * 1.0001f);
  }
  EXPECT_GT(deepest, 0u);
}

// The vLOD of every cell, computed afresh by the engine with the stored rule and the CLI's
// --refine 1: the oracle of the Δs.
std::map<CellId, std::vector<visibility::PieceId>> vlods_of(const World& world, const visibility::StoredVlod& stored) {
  EngineOptions options;
  options.refine_levels = 1;
  options.lod_rule = stored.rule();
  const auto engine = make_engine("vlod", world, options);
  const ViewCellPartition& cells = stored.partition();
  std::map<CellId, std::vector<visibility::PieceId>> out;
  for (CellId c = 0; c < cells.cell_count(); ++c)
    if (cells.cell(c).computed())
      out[c] = visibility::vlod_pieces(world, stored.pieces(), cells, c, engine->compute(cells.cell(c)).objects, stored.rule());
  return out;
}

// §2.3: every stored face Δ takes one cell's vLOD exactly to its neighbour's, in both
// directions, and every key cell's stored vLOD is its own; every cell is near a key cell.
TEST_F(VlodCity, FaceDeltasAndKeyCellsRebuildEveryVlod) {
  const std::string world_file = out_.file("deltas.cww");
  auto r = test::run_cellwalk("pvs " + world_ + " --engine vlod --cells octree:40:30000:2 --refine 1 --lod-height 72 -o " + world_file);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("vlod section"), std::string::npos) << r.output;
  const World world(world_file);
  const visibility::StoredVlod stored(world);
  const auto vlods = vlods_of(world, stored);
  ASSERT_GT(vlods.size(), 4u);
  uint64_t deltas = 0, keys = 0, changed = 0;
  for (const auto& [c, vlod] : vlods) {
    EXPECT_TRUE(stored.has_vlod(c));
    if (stored.is_key(c)) {
      EXPECT_EQ(stored.key_vlod(c), vlod) << "key cell " << c;
      ++keys;
    }
    for (CellId n : stored.neighbours(c)) {
      const auto d = stored.delta(c, n);
      ASSERT_TRUE(d) << c << "→" << n;
      std::vector<visibility::PieceId> kept, to;
      std::set_difference(vlod.begin(), vlod.end(), d->removed.begin(), d->removed.end(), std::back_inserter(kept));
      std::set_union(kept.begin(), kept.end(), d->added.begin(), d->added.end(), std::back_inserter(to));
      EXPECT_EQ(to, vlods.at(n)) << c << "→" << n;
      ++deltas;
      changed += !d->added.empty() || !d->removed.empty();
    }
  }
  EXPECT_GT(deltas, 0u);
  EXPECT_GT(changed, 0u) << "every Δ empty: the test shows nothing";
  EXPECT_GT(keys, 0u);
  EXPECT_LT(keys, vlods.size());
}

// The run time's vLOD is the cell's whatever the route: single crossings, several cells in
// one frame, and teleports, checked against the oracle with culling off (select draws the vLOD).
TEST_F(VlodCity, TheRunTimeVlodIsTheCellsOwnAfterAnyMove) {
  const std::string world_file = out_.file("moves.cww");
  auto r = test::run_cellwalk("pvs " + world_ + " --engine vlod --cells grid:30 --refine 1 --lod-height 72 -o " + world_file);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const World world(world_file);
  const visibility::StoredVlod stored(world);
  const auto vlods = vlods_of(world, stored);
  VlodStrategy strategy(world, parse_vlod_strategy_name("vlod:cull=0,prefetch=0"), StrategyOptions{});
  Random rng(9);
  Aabb all;
  for (CellId c = 0; c < stored.partition().cell_count(); ++c) all.extend(stored.partition().cell(c).box);
  Camera camera;
  camera.position = all.center();
  camera.position.y = 1.7f;
  std::vector<DrawItem> items;
  for (int step = 0; step < 120; ++step) {
    const float reach = step % 10 == 9 ? 1000.0f : float(rng.uniform(1, 35));  // now and then a teleport
    camera.position.x = std::clamp(camera.position.x + float(rng.uniform(-reach, reach)), all.min.x + 0.1f, all.max.x - 0.1f);
    camera.position.z = std::clamp(camera.position.z + float(rng.uniform(-reach, reach)), all.min.z + 0.1f, all.max.z - 0.1f);
    FrameStats stats;
    strategy.select(camera, items, stats);
    const CellId c = *stored.partition().locate(camera.position);
    if (!stored.has_vlod(c)) continue;  // inside a building: the frame draws the frustum instead
    std::vector<visibility::PieceId> drawn;
    for (const DrawItem& item : items) drawn.push_back(stored.pieces().piece(item.id, item.lod));
    EXPECT_EQ(drawn, vlods.at(c)) << "step " << step << " in cell " << c;
  }
  EXPECT_GT(strategy.counters().cell_changes, 20u);
  EXPECT_GT(strategy.counters().crossings, strategy.counters().cell_changes) << "no move crossed intermediate cells";
  // Every change read a record or more (a key frame or Δs), each at least a byte.
  EXPECT_GE(strategy.counters().section_bytes_read, strategy.counters().cell_changes);
}

// Precompute at scale: two shards merged give the section one run gives, byte for byte.
TEST_F(VlodCity, ShardsMergeIntoTheSectionOfOneRun) {
  const std::string spec = " --engine vlod --cells grid:30 --refine 1 --lod-height 72";
  const std::string whole = out_.file("whole.cww"), merged = out_.file("merged.cww");
  auto r = test::run_cellwalk("pvs " + world_ + spec + " -o " + whole);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::string parts;
  for (const char* shard : {"0/2", "1/2"}) {
    const std::string part = out_.file(std::string("part") + shard[0]);
    r = test::run_cellwalk("pvs " + world_ + spec + " --shard " + shard + " -o " + part);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    parts += " " + part;
  }
  r = test::run_cellwalk("pvs " + world_ + " --merge" + parts + " -o " + merged);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("vlod section"), std::string::npos) << r.output;
  const World a(whole), b(merged);
  EXPECT_EQ(a.file().read_all(visibility::kVlodSection), b.file().read_all(visibility::kVlodSection));
}

// §3 applied: each layout moves the encoded levels, not their bytes; the world still verifies;
// the runs of the crossings' additions in the file's byte order are what pvs reports, fewest
// in the TSP layout; the Δs' ids are numbered in the file's byte order (§2.4), so their runs
// of ids are those runs; and `keep` leaves the geometry where it was.
TEST_F(VlodCity, DiskOrderMovesTheLevelsNotTheirBytes) {
  const World original(world_);
  std::map<std::string, uint64_t> runs;
  for (const std::string layout : {"keep", "morton", "tsp"}) {
    const std::string file = out_.file("layout-" + layout + ".cww");
    auto r = test::run_cellwalk("pvs " + world_ + " --engine vlod --cells grid:30 --refine 1 --lod-height 72 --json --disk-order " +
                                layout + " -o " + file);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = test::json_output(r);
    ASSERT_TRUE(j.contains("vlod")) << r.output;
    ASSERT_EQ(test::run_cellwalk("verify " + file).exit_code, 0) << layout;
    const World world(file);
    ASSERT_EQ(world.object_count(), original.object_count());
    bool moved = false;
    for (ObjectId id = 0; id < world.object_count(); ++id)
      for (uint32_t level = 0; level < world.object(id).lod_count; ++level) {
        ASSERT_EQ(world.read_level(id, level), original.read_level(id, level)) << layout << " " << id << "/" << level;
        moved |= world.lod(id, level).offset != original.lod(id, level).offset;
      }
    EXPECT_EQ(moved, layout != "keep") << layout;
    // R(M) in the file's byte order, from the stored Δs.
    const visibility::StoredVlod stored(world);
    std::vector<std::vector<uint32_t>> rows;
    for (CellId c = 0; c < stored.partition().cell_count(); ++c)
      for (CellId n : stored.neighbours(c))
        if (c < n) {
          const auto d = stored.delta(c, n);
          ASSERT_TRUE(d.has_value());
          for (const auto* row : {&d->added, &d->removed})
            if (!row->empty()) rows.push_back(*row);
        }
    ASSERT_FALSE(rows.empty());
    std::vector<uint32_t> by_offset(stored.pieces().count());
    std::iota(by_offset.begin(), by_offset.end(), 0u);
    auto offset = [&](uint32_t p) { return world.lod(stored.pieces().object(p), stored.pieces().level(p)).offset; };
    std::sort(by_offset.begin(), by_offset.end(), [&](uint32_t a, uint32_t b) { return offset(a) < offset(b); });
    runs[layout] = visibility::total_runs(rows, by_offset);
    EXPECT_EQ(runs[layout], j["vlod"]["runs_written"].get<uint64_t>()) << layout;
    // §2.4 renumbering: pieces are numbered in the file's byte order, so a run on disk is a run
    // of consecutive ids, which the run codecs store as one.
    EXPECT_EQ(by_offset, visibility::identity_order(uint32_t(by_offset.size()))) << layout;
  }
  EXPECT_LT(runs["tsp"], runs["keep"]);
  EXPECT_LE(runs["tsp"], runs["morton"]);
  // A k-d scene tree (conv, hdov) built on the world still belongs to it laid out anew.
  const std::string tree = out_.file("layout.scenetree");
  open_scene_tree(original, SceneTreeParams{}, tree);
  const World laid_out(out_.file("layout-tsp.cww"));
  EXPECT_NO_THROW(SceneTree(laid_out, tree));
  // A disk order is no option of another engine.
  EXPECT_NE(test::run_cellwalk("pvs " + world_ + " --engine sampling --disk-order tsp -o " + out_.file("x.cww")).exit_code, 0);
}

}  // namespace
}  // namespace cellwalk
