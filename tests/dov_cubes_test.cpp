// The DoV engine's fast cube-map modes against its GL reference (HDoV thesis §5.5.2, digest 000
// §3.9; issue 13): on a generated city and a bunny grid, every object's point DoV at each corner
// and region DoV per cell agree with `exact` within the silhouette tolerance derived below, and
// the same check rejects cube maps cast from a shifted origin or with a face flipped.
#include <gtest/gtest.h>

#include <map>

#include "cellwalk/precompute/engine.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "precompute/cell_points.hpp"
#include "cellwalk/core/error.hpp"
#include "precompute/dov_engine.hpp"
#include "precompute/pvs_builder.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using visibility::CubeIds;

constexpr int kResolution = 64;

// Tolerance. Both modes sample the same level-0 surfaces at the same pixel centres (the rays go
// through the centres GL's rasteriser samples, with the same near and far planes), so a pixel's
// id can differ only where its centre lies within rounding of an edge between two objects'
// projections (or of two surfaces within depth precision, which these worlds do not have). Such
// a pixel shows, in whichever map gives it object o, o next to something else: it is a
// silhouette pixel of o there, one with an 8-neighbour of another id. So at a point
//   |DoV_fast(o) - DoV_exact(o)| <= Σ eq. 5.11 weights of o's silhouette pixels in either map,
// and, because |max_c a_c - max_c b_c| <= max_c |a_c - b_c|, the region DoVs (max over the 8
// corners) differ by at most the largest of those sums over the corners. The premise is checked
// too, pixel by pixel: every pixel whose ids differ is a silhouette pixel in one of the maps.
// DoVs alone could not catch a face flipped or two faces swapped (eq. 5.11 weights are the same
// on every face and symmetric in it); the pixel check does, and a shifted origin fails both.

// Whether pixel (i, j) of `face` has an 8-neighbour in the face with another id.
bool silhouette(const IdImage& face, int i, int j) {
  const int r = face.width;
  const uint32_t id = face.ids[size_t(j) * r + i];
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di)
      if (i + di >= 0 && i + di < r && j + dj >= 0 && j + dj < r && face.ids[size_t(j + dj) * r + i + di] != id) return true;
  return false;
}

// Pixels whose ids differ though neither map has a silhouette there.
size_t interior_mismatches(const CubeIds& exact, const CubeIds& fast) {
  size_t n = 0;
  for (size_t f = 0; f < 6; ++f)
    for (int j = 0; j < exact[f].width; ++j)
      for (int i = 0; i < exact[f].width; ++i) {
        const size_t px = size_t(j) * exact[f].width + i;
        n += exact[f].ids[px] != fast[f].ids[px] && !silhouette(exact[f], i, j) && !silhouette(fast[f], i, j);
      }
  return n;
}

struct PointDov {
  std::map<ObjectId, double> dov, silhouette;
};

PointDov point_dov(const CubeIds& faces, const std::vector<double>& weights) {
  PointDov out;
  for (const IdImage& face : faces)
    for (int j = 0; j < face.width; ++j)
      for (int i = 0; i < face.width; ++i) {
        const size_t px = size_t(j) * face.width + i;
        if (face.ids[px] == kBackgroundId) continue;
        out.dov[face.ids[px] - 1] += weights[px];
        if (silhouette(face, i, j)) out.silhouette[face.ids[px] - 1] += weights[px];
      }
  return out;
}

double value(const std::map<ObjectId, double>& m, ObjectId id) {
  auto it = m.find(id);
  return it == m.end() ? 0.0 : it->second;
}

// Objects whose point DoV differs by more than the tolerance, over both maps' objects.
std::vector<ObjectId> beyond_tolerance(const PointDov& exact, const PointDov& fast) {
  std::map<ObjectId, bool> ids;
  for (const auto& [id, d] : exact.dov) ids[id] = true;
  for (const auto& [id, d] : fast.dov) ids[id] = true;
  std::vector<ObjectId> out;
  for (const auto& [id, seen] : ids) {
    const double tolerance = value(exact.silhouette, id) + value(fast.silhouette, id) + 1e-9;
    if (std::abs(value(exact.dov, id) - value(fast.dov, id)) > tolerance) out.push_back(id);
  }
  return out;
}

std::string write_city(const test::TempDir& dir) {
  const std::string scene = dir.file("city.cwscene"), world = dir.file("city.cww");
  {
    SceneWriter writer(scene);
    writer.finish(generate_city(CityParams{.objects = 150, .seed = 3}, writer));
  }
  build_world(scene, world, BuildParams{});
  return world;
}

std::string write_bunny_grid(const test::TempDir& dir) {
  const std::string scene = dir.file("bunnies.cwscene"), world = dir.file("bunnies.cww");
  {
    SceneWriter writer(scene);
    writer.finish(generate_grid(GridParams{.mesh = test::cgal_mesh("bunny00.off"), .nx = 2, .ny = 1, .nz = 2}, writer));
  }
  build_world(scene, world, BuildParams{});
  return world;
}

struct Worlds {
  test::TempDir dir;
  std::string city = write_city(dir), bunnies = write_bunny_grid(dir);
};

// A few eye-height cells spread over a world: 20 m cells in the city, 0.4 m ones among the bunnies.
// `count` cells spread over a grid over the geometry alone (not the navigation graph beyond it),
// so they lie among the objects.
std::vector<ViewCell> cells_of(const World& world, float size, uint64_t count) {
  CellRegion region = default_cell_region(world.info().bounds, world.info().nav, true);
  region.bounds = world.info().bounds;
  const auto partition = make_grid_partition(region, size);
  std::vector<ViewCell> out;
  const uint64_t n = partition->cell_count();
  for (uint64_t i = 0; i < count; ++i) out.push_back(partition->cell(CellId((2 * i + 1) * n / (2 * count))));
  return out;
}

class DovCubesAgainstExact : public ::testing::TestWithParam<DovCubes> {
 protected:
  static void SetUpTestSuite() { worlds_ = new Worlds; }
  static void TearDownTestSuite() {
    delete worlds_;
    worlds_ = nullptr;
  }

  EngineOptions options(DovCubes cubes) const {
    EngineOptions o;
    o.dov_resolution = kResolution;
    o.dov_cubes = cubes;
    return o;
  }

  // Point DoVs at every corner, per corner and region against exact.
  void check_world(const std::string& file, float cell_size) const {
    const World world(file);
    const std::vector<double> weights = visibility::cube_pixel_weights(kResolution);
    const auto exact_maps = visibility::make_cube_maps(DovCubes::kExact, world, kResolution);
    const auto fast_maps = visibility::make_cube_maps(GetParam(), world, kResolution);
    const visibility::DovEngine exact(world, options(DovCubes::kExact));
    const visibility::DovEngine fast(world, options(GetParam()));
    size_t compared = 0;
    for (const ViewCell& cell : cells_of(world, cell_size, 3)) {
      std::map<ObjectId, double> tolerance;  // max over corners of the point tolerance
      for (const Vec3& corner : visibility::cell_corners(cell.box)) {
        const CubeIds exact_ids = exact_maps->render(corner), fast_ids = fast_maps->render(corner);
        EXPECT_EQ(interior_mismatches(exact_ids, fast_ids), 0u) << "corner of cell " << cell.id;
        const PointDov a = point_dov(exact_ids, weights), b = point_dov(fast_ids, weights);
        EXPECT_EQ(beyond_tolerance(a, b), std::vector<ObjectId>{}) << "corner of cell " << cell.id;
        for (const auto& [id, d] : a.dov) tolerance[id] = std::max(tolerance[id], value(a.silhouette, id) + value(b.silhouette, id));
        for (const auto& [id, d] : b.dov) tolerance[id] = std::max(tolerance[id], value(a.silhouette, id) + value(b.silhouette, id));
      }
      const VisibleSet e = exact.compute(cell), f = fast.compute(cell);
      std::map<ObjectId, double> de, df;
      for (size_t i = 0; i < e.objects.size(); ++i) de[e.objects[i]] = e.dov[i];
      for (size_t i = 0; i < f.objects.size(); ++i) df[f.objects[i]] = f.dov[i];
      // The region DoVs, and the sets: an object only one mode sees is one below the tolerance.
      for (const auto& [id, t] : tolerance) {
        EXPECT_NEAR(value(df, id), value(de, id), t + 1e-6) << "object " << id << " in cell " << cell.id;
        if (de.count(id) != df.count(id)) {
          EXPECT_LE(value(de, id) + value(df, id), t + 1e-6) << "object " << id << " in one set only";
        }
      }
      for (const auto& [id, d] : de) EXPECT_TRUE(tolerance.count(id)) << id;
      for (const auto& [id, d] : df) EXPECT_TRUE(tolerance.count(id)) << id;
      compared += e.objects.size();
    }
    EXPECT_GT(compared, 10u) << "the cells must see something";
  }

  static Worlds* worlds_;
};

Worlds* DovCubesAgainstExact::worlds_ = nullptr;

TEST_P(DovCubesAgainstExact, CityDovsAgreeWithinTheSilhouetteTolerance) { check_world(worlds_->city, 20.0f); }

TEST_P(DovCubesAgainstExact, BunnyGridDovsAgreeWithinTheSilhouetteTolerance) { check_world(worlds_->bunnies, 0.4f); }

// The check can fail: maps cast 1.5 m from the point fail the DoV tolerance, and those, or
// maps with one face upside down or two faces swapped, fail the pixel check, at every checked
// point (corners that see at least 8 objects, not ones inside a building, which see only its walls).
TEST_P(DovCubesAgainstExact, ToleranceRejectsAShiftedOriginAndFlippedFaces) {
  const World world(worlds_->city);
  const std::vector<double> weights = visibility::cube_pixel_weights(kResolution);
  const auto exact_maps = visibility::make_cube_maps(DovCubes::kExact, world, kResolution);
  const auto fast_maps = visibility::make_cube_maps(GetParam(), world, kResolution);
  int checked = 0;
  for (const ViewCell& cell : cells_of(world, 20.0f, 8)) {
    const Vec3 p = cell.box.min;
    const CubeIds exact_ids = exact_maps->render(p);
    const PointDov a = point_dov(exact_ids, weights);
    if (a.dov.size() < 8) continue;
    EXPECT_EQ(interior_mismatches(exact_ids, fast_maps->render(p)), 0u);
    const CubeIds shifted = fast_maps->render(p + Vec3(1.5f, 0.0f, 0.0f));
    EXPECT_NE(beyond_tolerance(a, point_dov(shifted, weights)), std::vector<ObjectId>{});
    EXPECT_GT(interior_mismatches(exact_ids, shifted), 0u);
    CubeIds flipped = fast_maps->render(p);
    for (int j = 0; j < kResolution / 2; ++j)
      std::swap_ranges(flipped[0].ids.begin() + j * kResolution, flipped[0].ids.begin() + (j + 1) * kResolution,
                       flipped[0].ids.begin() + (kResolution - 1 - j) * kResolution);
    EXPECT_GT(interior_mismatches(exact_ids, flipped), 0u);
    CubeIds swapped = fast_maps->render(p);
    std::swap(swapped[1], swapped[3]);
    EXPECT_GT(interior_mismatches(exact_ids, swapped), 0u);
    if (++checked == 2) break;
  }
  EXPECT_EQ(checked, 2) << "no cell corner of the city sees 8 objects";
}

// The fast modes keep the point DoVs of recent corners for the cells that share them: a cell
// computed after its neighbour gets exactly what it gets on its own.
TEST(DovEngineCornerCache, SharedCornersGiveTheSameDovs) {
  test::TempDir dir;
  const World world(test::write_street_world(dir, 12));
  const auto partition = make_grid_partition(default_cell_region(world.info().bounds, world.info().nav, true), 4.0f);
  EngineOptions o;
  o.dov_resolution = kResolution;
  const visibility::DovEngine warm(world, o);
  size_t compared = 0;
  for (CellId c = 0; c < partition->cell_count(); c += 3) {
    for (CellId n : partition->face_neighbours(c)) warm.compute(partition->cell(n));
    const visibility::DovEngine cold(world, o);
    const VisibleSet a = warm.compute(partition->cell(c)), b = cold.compute(partition->cell(c));
    EXPECT_EQ(a.objects, b.objects) << c;
    EXPECT_EQ(a.dov, b.dov) << c;
    compared += a.objects.size();
  }
  EXPECT_GT(compared, 0u);
}

// A checkpoint of one cube-map mode is not resumed by another: the mode is in the run identity.
TEST(DovEngineRunIdentity, ACheckpointOfOneModeIsRefusedByAnother) {
  test::TempDir dir;
  const World world(test::write_street_world(dir, 6));
  const auto partition = make_grid_partition(default_cell_region(world.info().bounds, world.info().nav, true), 8.0f);
  EngineOptions rays;
  rays.dov_resolution = 16;
  rays.sample_points = 1;
  rays.rays_per_point = 64;
  EngineOptions exact = rays;
  exact.dov_cubes = DovCubes::kExact;
  const auto engine = make_engine("dov", world, rays);
  const visibility::PvsRun rays_run = visibility::make_pvs_run(*engine, "grid:8", rays);
  const visibility::PvsRun exact_run = visibility::make_pvs_run(*engine, "grid:8", exact);
  EXPECT_NE(rays_run.settings.find("cubes=rays"), std::string::npos) << rays_run.settings;
  EXPECT_NE(exact_run.settings.find("cubes=exact"), std::string::npos) << exact_run.settings;
  visibility::compute_cell_sets(world, *engine, *partition, rays_run, dir.file("ck"));
  EXPECT_THROW(visibility::compute_cell_sets(world, *engine, *partition, exact_run, dir.file("ck")), Error);
  EXPECT_NO_THROW(visibility::compute_cell_sets(world, *engine, *partition, rays_run, dir.file("ck")));
}

INSTANTIATE_TEST_SUITE_P(DovEngine, DovCubesAgainstExact, ::testing::Values(DovCubes::kRays),
                         [](const ::testing::TestParamInfo<DovCubes>& info) { return dov_cubes_name(info.param); });

}  // namespace
}  // namespace cellwalk
