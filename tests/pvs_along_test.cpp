// `cellwalk pvs --along PATH --along-margin M` (issue 13): only the cells near a camera path get
// a set; the others are stored as skipped, never as empty or solid, and every consumer refuses
// to walk into one instead of showing the wrong objects.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "precompute/pvs_builder.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// Eye-height frames down the street from x = a to x = b (z = 0), one every `step` metres.
CameraPath street_path(float a, float b, float step = 0.5f) {
  CameraPath path;
  for (float x = a; x <= b; x += step) path.frames.push_back(PathFrame{double(path.frames.size()) / 10.0, Vec3(x, 1.7f, 0.0f), 90.0f, 0.0f});
  return path;
}

// The largest per-axis distance from p to `box` (0 inside): p lies in the box grown by m on
// every side exactly when this is <= m.
float chebyshev(const Vec3& p, const Aabb& box) {
  float d = 0.0f;
  for (int a = 0; a < 3; ++a) d = std::max({d, box.min[a] - p[a], p[a] - box.max[a]});
  return d;
}

// The oracle: the polyline sampled every 2 cm, so a cell within margin - 2 cm of it is found.
float path_distance(const CameraPath& path, const Aabb& box) {
  float best = INFINITY;
  for (size_t i = 0; i + 1 < path.frames.size(); ++i) {
    const Vec3 a = path.frames[i].position, b = path.frames[i + 1].position;
    const int steps = std::max(1, int(glm::length(b - a) / 0.02f));
    for (int s = 0; s <= steps; ++s) best = std::min(best, chebyshev(a + (b - a) * (float(s) / float(steps)), box));
  }
  return best;
}

TEST(PvsAlong, ComputesOnlyTheCellsNearThePathAndStoresTheRestSkipped) {
  test::TempDir dir;
  const std::string file = test::write_street_world(dir, 16);
  const World world(file);
  const visibility::EmbreeScene scene(world);
  const auto all = visibility::make_partition("grid:4", world, scene);
  const CameraPath path = street_path(6.0f, 14.0f);
  constexpr float kMargin = 3.0f;
  const auto along = visibility::cells_along(*all, path, kMargin);
  ASSERT_EQ(along->cell_count(), all->cell_count());
  size_t kept = 0, skipped = 0;
  for (CellId c = 0; c < all->cell_count(); ++c) {
    const ViewCell& a = all->cell(c);
    const ViewCell& b = along->cell(c);
    EXPECT_EQ(b.box.min, a.box.min);
    EXPECT_EQ(b.solid, a.solid);
    EXPECT_EQ(along->face_neighbours(c), all->face_neighbours(c));
    if (a.solid) continue;
    const float d = path_distance(path, a.box);
    if (d <= kMargin - 0.02f) {
      EXPECT_FALSE(b.skipped) << c << " at " << d << " m";
    } else if (d > kMargin) {
      EXPECT_TRUE(b.skipped) << c << " at " << d << " m";
    }
    (b.skipped ? skipped : kept) += 1;
  }
  EXPECT_GT(kept, 0u);
  EXPECT_GT(skipped, kept) << "the street is longer than the path";

  EngineOptions options;
  options.rays_per_point = 256;
  options.sample_points = 2;
  const auto engine = make_engine("sampling", world, options);
  const visibility::PvsRun run = visibility::make_pvs_run(*engine, "grid:4", options);
  // A checkpoint of the whole grid is a different run: its cells differ in what they skip.
  visibility::compute_cell_sets(world, *engine, *all, run, dir.file("ck"));
  EXPECT_THROW(visibility::compute_cell_sets(world, *engine, *along, run, dir.file("ck")), Error);
  std::filesystem::remove(dir.file("ck"));
  const visibility::CellSets sets = visibility::compute_cell_sets(world, *engine, *along, run, dir.file("ck"));
  EXPECT_EQ(sets.size(), kept);
  const std::string out = dir.file("along.cww");
  visibility::write_world_with_pvs(world, out, *along, sets, run);
  const World stored(out);
  const visibility::StoredPvs pvs(stored);
  for (CellId c = 0; c < all->cell_count(); ++c) {
    ASSERT_EQ(pvs.partition().cell(c).skipped, along->cell(c).skipped) << c;
    if (along->cell(c).skipped) {
      EXPECT_THROW(pvs.set(c), Error) << c;
    } else if (!along->cell(c).solid) {
      EXPECT_EQ(pvs.set(c)->objects, sets.at(c).objects) << c;
    }
  }
  EXPECT_THROW(visibility::cells_along(*all, CameraPath{}, 1.0f), Error);
  EXPECT_THROW(visibility::cells_along(*all, path, -1.0f), Error);
}

// Through the commands: DoVs along half the street, the HDoV-tree from them; a walk inside the
// computed cells runs, one that walks on into skipped cells is refused with one line naming
// the cell, for VISUAL and for the scene-tree strategies that read the DoVs directly.
TEST(PvsAlong, AWalkIntoASkippedCellIsRefused) {
  test::TempDir dir;
  const std::string world = test::write_street_world(dir, 16);
  write_path(street_path(1.0f, 12.0f), dir.file("near.path"));
  write_path(street_path(1.0f, 40.0f), dir.file("far.path"));
  auto r = test::run_cellwalk("pvs " + world + " --engine dov --dov-resolution 16 --points 2 --rays 256 --cells grid:4 --along " +
                              dir.file("near.path") + " --along-margin 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(" skipped off the --along path"), std::string::npos) << r.output;
  r = test::run_cellwalk("visual-build " + world);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string strategy : {"visual", "hdov-vsc"}) {
    r = test::run_cellwalk("walk " + world + " --path " + dir.file("near.path") + " --strategy " + strategy +
                           " --width 64 --height 48 -o " + dir.file("near-" + strategy));
    EXPECT_EQ(r.exit_code, 0) << strategy << ": " << r.output;
    r = test::run_cellwalk("walk " + world + " --path " + dir.file("far.path") + " --strategy " + strategy +
                           " --width 64 --height 48 -o " + dir.file("far-" + strategy));
    EXPECT_EQ(r.exit_code, 1) << strategy << ": " << r.output;
    EXPECT_NE(r.output.find("which `cellwalk pvs --along` left out"), std::string::npos) << strategy << ": " << r.output;
  }
}

// Bad --along input: one line naming the option, non-zero exit, nothing written.
TEST(PvsAlong, BadOptionsAreRefused) {
  test::TempDir dir;
  const std::string world = test::write_street_world(dir, 4);
  write_path(CameraPath{}, dir.file("empty.path"));
  const auto refused = [&](const std::string& args, const std::string& needle) {
    const auto r = test::run_cellwalk("pvs " + world + " --cells grid:4 -o " + dir.file("out.cww") + " " + args);
    EXPECT_TRUE(r.exit_code > 0 && r.exit_code < 128) << args << ": " << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << args << ": " << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.cww"))) << args;
  };
  refused("--along-margin 2", "--along");
  refused("--along " + dir.file("none.path"), "none.path");
  refused("--along " + dir.file("empty.path"), "no frames");
  refused("--along " + dir.file("empty.path") + " --along-margin -1", "--along-margin");
  refused("--engine dov --dov-cubes fast", "--dov-cubes 'fast'");
  refused("--engine sampling --dov-compare 2", "--engine dov");
}

}  // namespace
}  // namespace cellwalk
