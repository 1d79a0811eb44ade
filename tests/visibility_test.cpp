// Tests of the visibility engines on worlds whose answer is known by construction (issue 4):
// a wall hiding a box, a gap that reveals it, an object visible only from one corner of the
// cell. Every engine and the ground truth are checked against them; DoV weights and values;
// the PVS builder's storage, shards, merge and resume.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "test_support.hpp"
#include "precompute/dov_engine.hpp"
#include "precompute/ground_truth.hpp"
#include "precompute/pvs_builder.hpp"
#include "visibility/set_codec.hpp"

namespace cellwalk {
namespace {

Object box_object(ObjectId id, Vec3 min, Vec3 max) {
  Object o;
  o.id = id;
  o.name = "box" + std::to_string(id);
  o.mesh = test::box_mesh(Aabb{min, max});
  return o;
}

// The same objects written double-sided (every triangle also in the opposite winding): they
// stop the same rays but enclose nothing.
std::vector<Object> two_sided(std::vector<Object> objects) {
  for (Object& o : objects) o.mesh = test::double_sided(o.mesh);
  return objects;
}

// The cell every scene is seen from: 2 m cube at the origin.
const ViewCell kCell{0, Aabb{Vec3(0.0f), Vec3(2.0f)}, 0, false};

// A 100 m wide, 30 m tall wall at z = -5 in front of the cell, split by a gap of `gap` metres
// at x = 1 (none when 0); a 2 m box behind it at z = -12. The box (the last id) is hidden
// exactly when there is no gap.
std::vector<Object> wall_scene(float gap) {
  std::vector<Object> objects;
  if (gap > 0) {
    objects.push_back(box_object(0, {-50, -10, -5.5f}, {1 - gap / 2, 30, -5}));
    objects.push_back(box_object(1, {1 + gap / 2, -10, -5.5f}, {50, 30, -5}));
  } else {
    objects.push_back(box_object(0, {-50, -10, -5.5f}, {50, 30, -5}));
  }
  objects.push_back(box_object(ObjectId(objects.size()), {0, 0, -13}, {2, 2, -11}));
  return objects;
}

// A 100 m wall at z = -1 with a 0.3 m hole on the line from the cell's corner K = (2, 2, 0)
// along -(1, 1, 1), and a 2 m box further along it. That line touches the cell only at K (it
// leaves through x > 2, y > 2 and arrives from z < 0), so only points near K see the box.
std::vector<Object> corner_scene() {
  const float h = 0.15f, cx = 0.99f, cy = 0.99f, z0 = -1.02f, z1 = -1.0f;
  return {box_object(0, {-50, -50, z0}, {cx - h, 50, z1}), box_object(1, {cx + h, -50, z0}, {50, 50, z1}),
          box_object(2, {cx - h, -50, z0}, {cx + h, cy - h, z1}), box_object(3, {cx - h, cy + h, z0}, {cx + h, 50, z1}),
          box_object(4, {-5, -5, -7}, {-3, -3, -5})};
}

struct Worlds {
  test::TempDir dir;
  std::string hidden = test::write_world(dir, wall_scene(0), NavGraph{}, "hidden");
  std::string gap = test::write_world(dir, wall_scene(1.0f), NavGraph{}, "gap");
  std::string corner = test::write_world(dir, corner_scene(), NavGraph{}, "corner");
  std::string hidden_two_sided = test::write_world(dir, two_sided(wall_scene(0)), NavGraph{}, "hidden2");
  std::string gap_two_sided = test::write_world(dir, two_sided(wall_scene(1.0f)), NavGraph{}, "gap2");
  std::string corner_two_sided = test::write_world(dir, two_sided(corner_scene()), NavGraph{}, "corner2");
};

bool has(const std::vector<ObjectId>& ids, ObjectId id) { return std::find(ids.begin(), ids.end(), id) != ids.end(); }

class Visibility : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { worlds_ = new Worlds; }
  static void TearDownTestSuite() { delete worlds_; }
  static Worlds* worlds_;
};
Worlds* Visibility::worlds_ = nullptr;

TEST_F(Visibility, WallHidesTheBox) {
  const World world(worlds_->hidden);
  for (const std::string& name : engine_names())
    EXPECT_FALSE(has(make_engine(name, world)->compute(kCell).objects, 1)) << name;
  const visibility::CubeMapRenderer cube(world, 512);
  EXPECT_FALSE(has(visibility::ground_truth_visible(cube, kCell, {}), 1));
}

// A double-sided wall hides the box just as well, but encloses nothing, so a conservative
// engine cannot prove it; whatever it proves, it keeps all the ground truth sees.
TEST_F(Visibility, DoubleSidedWallHidesTheBoxAndConservativeEnginesKeepTheTruth) {
  const World world(worlds_->hidden_two_sided);
  const visibility::CubeMapRenderer cube(world, 512);
  const std::vector<ObjectId> truth = visibility::ground_truth_visible(cube, kCell, {});
  EXPECT_FALSE(has(truth, 1));
  EXPECT_TRUE(has(truth, 0));
  for (const std::string& name : engine_names()) {
    const auto engine = make_engine(name, world);
    if (!engine->conservative()) continue;
    const std::vector<ObjectId> set = engine->compute(kCell).objects;
    for (ObjectId id : truth) EXPECT_TRUE(has(set, id)) << name << " misses " << id;
  }
}

TEST_F(Visibility, GapRevealsTheBoxToEveryEngine) {
  for (const std::string* file : {&worlds_->gap, &worlds_->gap_two_sided}) {
    const World world(*file);
    for (const std::string& name : engine_names())
      EXPECT_TRUE(has(make_engine(name, world)->compute(kCell).objects, 2)) << name << " " << *file;
    const visibility::CubeMapRenderer cube(world, 512);
    EXPECT_TRUE(has(visibility::ground_truth_visible(cube, kCell, {}), 2)) << *file;
  }
}

TEST_F(Visibility, ObjectSeenOnlyFromOneCorner) {
  for (const std::string* file : {&worlds_->corner, &worlds_->corner_two_sided}) {
    const World world(*file);
    const visibility::CubeMapRenderer cube(world, 512);
    auto seen_from = [&](Vec3 p) {
      for (const IdImage& face : cube.render(p))
        if (std::find(face.ids.begin(), face.ids.end(), 4u + 1u) != face.ids.end()) return true;
      return false;
    };
    EXPECT_TRUE(seen_from({2, 2, 0})) << *file;
    EXPECT_FALSE(seen_from({1, 1, 1})) << *file;
    EXPECT_FALSE(seen_from({0, 2, 0})) << *file;
    EXPECT_FALSE(seen_from({2, 0, 0})) << *file;
    for (const std::string& name : engine_names())
      EXPECT_TRUE(has(make_engine(name, world)->compute(kCell).objects, 4)) << name << " " << *file;
    EXPECT_TRUE(has(visibility::ground_truth_visible(cube, kCell, {}), 4)) << *file;
  }
}

TEST(DegreeOfVisibility, PixelWeightsSumToOne) {
  for (int r : {16, 64, 256}) {
    const std::vector<double> w = visibility::cube_pixel_weights(r);
    double sum = 0.0;
    for (double x : w) sum += x;
    EXPECT_NEAR(6.0 * sum, 1.0, 1e-6) << r;
    // The thesis's midpoint form is close but not exact: its error shrinks as 1/R².
    const std::vector<double> m = visibility::cube_pixel_weights(r, true);
    double msum = 0.0;
    for (double x : m) msum += x;
    EXPECT_NEAR(6.0 * msum, 1.0, 2.0 / (r * r)) << r;
    // Centre pixels subtend the most, corner pixels the least (DoV_s).
    EXPECT_GT(w[size_t(r / 2) * r + r / 2], w[0]);
  }
}

TEST_F(Visibility, DovValuesAreFractionsOfTheSphere) {
  const World world(worlds_->gap);
  EngineOptions options;
  options.dov_resolution = 128;
  const visibility::DovEngine dov(world, options);
  const VisibleSet set = dov.compute(kCell);
  ASSERT_EQ(set.dov.size(), set.objects.size());
  for (float d : set.dov) {
    EXPECT_GT(d, 0.0f);
    EXPECT_LE(d, 1.0f);
  }
  // The wall fills almost half the sphere from the cell's corner nearest to it.
  EXPECT_GT(set.dov[0] + set.dov[1], 0.35f);
  const CornerDov corners = dov.compute_corners(kCell);
  ASSERT_EQ(corners.dov.size(), 8u);
  for (const auto& row : corners.dov) {
    double sum = 0.0;
    for (float d : row) sum += d;
    EXPECT_LE(sum, 1.0 + 1e-5);
  }
  const float all = group_dov(corners, set.objects);
  EXPECT_LE(all, 1.0f + 1e-5f);
  for (float d : set.dov) EXPECT_GE(all + 1e-6f, d);
  EXPECT_GE(group_dov_upper_bound(set, set.objects) + 1e-6f, all);
}

TEST(DegreeOfVisibility, EnclosingObjectHasDovOne) {
  test::TempDir dir;
  const World world(test::write_world(dir, {box_object(0, Vec3(-10.0f), Vec3(10.0f))}, NavGraph{}));
  EngineOptions options;
  options.dov_resolution = 64;
  const VisibleSet set = visibility::DovEngine(world, options).compute(kCell);
  ASSERT_EQ(set.objects, std::vector<ObjectId>{0});
  EXPECT_NEAR(set.dov[0], 1.0f, 1e-5f);
}

TEST_F(Visibility, SamplingIsNotConservativeAndSaysSo) {
  const World world(worlds_->gap);
  EXPECT_FALSE(make_engine("sampling", world)->conservative());
  EXPECT_THROW(make_engine("no-such-engine", world), Error);
}

// The street world through the whole pipeline: sets stored and read back, shards merged to the
// same file contents, and a run resumed from a torn checkpoint.
TEST(PvsBuilder, StoresShardsMergesAndResumes) {
  test::TempDir dir;
  const std::string file = test::write_street_world(dir, 16);
  const World world(file);
  const visibility::EmbreeScene scene(world);
  const auto partition = visibility::make_partition("grid:8", world, scene);
  EngineOptions options;
  options.rays_per_point = 512;
  options.sample_points = 4;
  const auto engine = make_engine("sampling", world, options);
  visibility::PvsRun run{"sampling", false, "grid:8 test"};
  const visibility::CellSets sets = visibility::compute_cell_sets(world, *engine, *partition, run, dir.file("ck"));
  const std::string out = dir.file("with-pvs.cww");
  const visibility::PvsSizes sizes = visibility::write_world_with_pvs(world, out, *partition, sets, run);
  EXPECT_EQ(sizes.cells, partition->cell_count());
  // 16 objects: a bitmask is 2 bytes a cell, hard to beat; Δs are only taken when shorter.
  EXPECT_EQ(sizes.bitmask_bytes, 2 * sizes.cells_with_sets);
  EXPECT_LE(sizes.stored_bytes, sizes.full_bytes + sizes.cells - sizes.cells_with_sets);
  {
    const World stored(out);
    EXPECT_EQ(stored.object_count(), world.object_count());
    const visibility::StoredPvs pvs(stored);
    ASSERT_EQ(pvs.partition().cell_count(), partition->cell_count());
    for (const auto& [cell, set] : sets) EXPECT_EQ(pvs.set(cell)->objects, set.objects) << cell;
  }
  // Shards: two halves, the second interrupted (its checkpoint torn) and resumed.
  visibility::PvsRun half = run;
  half.shards = 2;
  half.shard = 0;
  visibility::compute_cell_sets(world, *engine, *partition, half, dir.file("p0"));
  half.shard = 1;
  visibility::compute_cell_sets(world, *engine, *partition, half, dir.file("p1"));
  std::filesystem::resize_file(dir.file("p1"), std::filesystem::file_size(dir.file("p1")) - 5);
  EXPECT_THROW(visibility::compute_cell_sets(world, *engine, *partition, run, dir.file("p1")), Error);  // other run
  visibility::compute_cell_sets(world, *engine, *partition, half, dir.file("p1"));
  const auto merged = test::run_cellwalk("pvs " + file + " --merge " + dir.file("p0") + " " + dir.file("p1") + " -o " + dir.file("merged.cww"));
  ASSERT_EQ(merged.exit_code, 0) << merged.output;
  const World m(dir.file("merged.cww"));
  const visibility::StoredPvs pvs(m);
  for (const auto& [cell, set] : sets) EXPECT_EQ(pvs.set(cell)->objects, set.objects) << cell;
}

// A disk that fills while `pvs` creates its checkpoint leaves it empty, and damage can hit its
// header; either once blocked every later run. Such a checkpoint is now discarded with a
// one-line warning and the run gives exactly a clean run's sets; an intact checkpoint of another
// run is still refused (StoresShardsMergesAndResumes).
TEST(PvsBuilder, CheckpointWithADamagedHeaderIsDiscardedAndTheRunStartsOver) {
  test::TempDir dir;
  const World world(test::write_street_world(dir, 16));
  const visibility::EmbreeScene scene(world);
  const auto partition = visibility::make_partition("grid:8", world, scene);
  EngineOptions options;
  options.rays_per_point = 256;
  options.sample_points = 2;
  const auto engine = make_engine("sampling", world, options);
  const visibility::PvsRun run{"sampling", false, "grid:8 test"};
  const std::string clean = dir.file("clean");
  const visibility::CellSets expected = visibility::compute_cell_sets(world, *engine, *partition, run, clean);
  ASSERT_FALSE(expected.empty());
  const std::vector<uint8_t> complete = test::slurp(clean);
  const auto same_sets = [&](const visibility::CellSets& sets) {
    if (sets.size() != expected.size()) return false;
    for (const auto& [cell, set] : expected)
      if (!sets.count(cell) || sets.at(cell).objects != set.objects) return false;
    return true;
  };
  // Damage: empty, a torn magic, a torn header, and one flipped byte in the magic, the run
  // hash, the settings and the header's own checksum (docs/format.md, "Checkpoints").
  const std::string ck = dir.file("ck");
  std::vector<std::vector<uint8_t>> damaged = {{}, {'C', 'W', 'P'}, {complete.begin(), complete.begin() + 30}};
  const size_t header_bytes = 8 + 8 + 4 + 4 + 4 + run.engine.size() + 1 + 4 + run.settings.size() + 4 +
                              serialize_partition(*partition).size() + 8;
  for (size_t at : {size_t(0), size_t(9), size_t(8 + 8 + 4 + 4 + 4 + run.engine.size() + 1 + 4), header_bytes - 1}) {
    std::vector<uint8_t> bytes = complete;
    bytes[at] ^= 0x10;
    damaged.push_back(bytes);
  }
  for (const std::vector<uint8_t>& bytes : damaged) {
    test::spit(ck, bytes);
    testing::internal::CaptureStderr();
    const visibility::CellSets sets = visibility::compute_cell_sets(world, *engine, *partition, run, ck);
    const std::string warning = testing::internal::GetCapturedStderr();
    EXPECT_TRUE(same_sets(sets)) << bytes.size() << " bytes";
    EXPECT_EQ(warning.rfind("cellwalk: warning: " + ck + "@", 0), 0u) << warning;
    EXPECT_NE(warning.find("discarded"), std::string::npos) << warning;
    EXPECT_EQ(std::count(warning.begin(), warning.end(), '\n'), 1) << warning;
    // The checkpoint written anew resumes like any other: no warning, every cell reused.
    std::optional<std::pair<uint64_t, uint64_t>> first;  // (cells done, total) at the start
    testing::internal::CaptureStderr();
    const auto again = visibility::compute_cell_sets(world, *engine, *partition, run, ck, [&](uint64_t done, uint64_t all) {
      if (!first) first = std::pair(done, all);
    });
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    EXPECT_TRUE(same_sets(again));
    ASSERT_TRUE(first.has_value());
    EXPECT_EQ(first->first, first->second);
  }
}

// The command as the issue ran it: an empty checkpoint left by a full disk no longer blocks pvs.
TEST(PvsCommand, EmptyCheckpointLeftByAFullDiskIsDiscardedWithAWarning) {
  test::TempDir dir;
  const std::string file = test::write_street_world(dir, 8);
  test::spit(file + ".pvs-checkpoint", {});
  const auto r = test::run_cellwalk("pvs " + file + " --engine sampling --cells grid:10 --points 2 --rays 64");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cellwalk: warning: " + file + ".pvs-checkpoint@0: truncated"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(file + ".pvs-checkpoint"));
  EXPECT_TRUE(visibility::StoredPvs(World(file)).partition().cell_count() > 0);
}

// Each cell's record is the smallest of gap-coded ids, a bitmask and a Δ from a neighbour, so
// the stored sets never exceed a bitmask and a form byte per cell, whatever their density;
// they read back exactly.
TEST(PvsBuilder, StoredSetsNeverExceedABitmask) {
  test::TempDir dir;
  const World world(test::write_street_world(dir, 40));
  const visibility::EmbreeScene scene(world);
  const auto partition = visibility::make_partition("grid:8", world, scene);
  Random rng(17);
  for (double density : {0.05, 0.6, 1.0}) {
    visibility::CellSets sets;
    for (CellId c = 0; c < partition->cell_count(); ++c) {
      if (partition->cell(c).solid) continue;
      VisibleSet& set = sets[c];
      for (ObjectId id = 0; id < world.object_count(); ++id)
        if (rng.chance(density)) set.objects.push_back(id);
    }
    const visibility::PvsRun run{"sampling", false, "codec test"};
    const std::string out = dir.file("codec.cww");
    const visibility::PvsSizes sizes = visibility::write_world_with_pvs(world, out, *partition, sets, run);
    EXPECT_EQ(sizes.bitmask_bytes, visibility::bitmask_bytes(world.object_count()) * sizes.cells_with_sets);
    EXPECT_LE(sizes.stored_bytes, sizes.bitmask_bytes + sizes.cells) << density;
    if (density >= 0.6) {
      EXPECT_LT(sizes.stored_bytes, sizes.full_bytes) << density;  // gaps cost a byte per id
    }
    const World stored(out);
    const visibility::StoredPvs pvs(stored);
    for (const auto& [cell, set] : sets) EXPECT_EQ(pvs.set(cell)->objects, set.objects) << cell;
  }
}

TEST(PvsCommand, ChecksAnEngineAgainstGroundTruth) {
  test::TempDir dir;
  const std::string file = test::write_street_world(dir, 12);
  const auto r = test::run_cellwalk("pvs " + file + " --engine sampling --cells grid:10 --check 2 --truth-points 2 "
                                    "--truth-resolution 256 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  EXPECT_EQ(j["checked"], 2);
  EXPECT_GE(j["recall"].get<double>(), 0.9);
  const auto dov = test::run_cellwalk("pvs " + file + " --engine dov --dov-resolution 64 --cells grid:20 -o " + dir.file("d.cww"));
  ASSERT_EQ(dov.exit_code, 0) << dov.output;
  const World world(dir.file("d.cww"));
  const visibility::StoredPvs pvs(world);
  EXPECT_TRUE(pvs.has_dov());
  EXPECT_EQ(pvs.engine(), "dov");
}

}  // namespace
}  // namespace cellwalk
