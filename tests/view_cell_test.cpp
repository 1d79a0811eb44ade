// Tests of the view-cell partitions (grid, octree with vLOD's rules, k-d after the stratified
// thesis): point location, face neighbours across levels, solid cells, stored form.
#include "cellwalk/visibility/view_cell.hpp"

#include <gtest/gtest.h>

#include <map>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/store/world.hpp"
#include "test_support.hpp"
#include "precompute/embree_scene.hpp"

namespace cellwalk {
namespace {

CellRegion region_2d(Vec3 min, Vec3 max) {
  CellRegion r;
  r.bounds.min = min;
  r.bounds.max = max;
  return r;
}

// Area over which two boxes touch across `axis` (0 if they do not share that face).
double shared_face_area(const Aabb& a, const Aabb& b, int axis) {
  if (a.max[axis] != b.min[axis] && b.max[axis] != a.min[axis]) return 0.0;
  double area = 1.0;
  for (int t = 0; t < 3; ++t)
    if (t != axis) area *= std::max(0.0f, std::min(a.max[t], b.max[t]) - std::max(a.min[t], b.min[t]));
  return area;
}

Aabb covered(const CellRegion& r) {
  Aabb b = r.bounds;
  if (r.two_d) {
    b.min.y = r.eye_min;
    b.max.y = r.eye_max;
  }
  return b;
}

// What must hold for every partition: cells tile the region, locate() finds the cell holding
// the point, and each inner face is exactly covered by the neighbours' faces (across levels).
void check_partition(const ViewCellPartition& p, const Aabb& bounds) {
  double volume = 0.0;
  for (CellId c = 0; c < p.cell_count(); ++c) {
    ASSERT_EQ(p.cell(c).id, c);
    const Vec3 s = p.cell(c).box.size();
    volume += double(s.x) * s.y * s.z;
  }
  const Vec3 s = bounds.size();
  EXPECT_NEAR(volume, double(s.x) * s.y * s.z, 1e-3 * double(s.x) * s.y * s.z);
  Random rng(9);
  for (int i = 0; i < 500; ++i) {
    const Vec3 q(rng.uniform(bounds.min.x, bounds.max.x), rng.uniform(bounds.min.y, bounds.max.y),
                 rng.uniform(bounds.min.z, bounds.max.z));
    const auto c = p.locate(q);
    ASSERT_TRUE(c.has_value());
    EXPECT_TRUE(p.cell(*c).box.contains(q));
  }
  EXPECT_FALSE(p.locate(bounds.max + Vec3(1.0f)).has_value());
  for (CellId c = 0; c < p.cell_count(); ++c) {
    const Aabb& box = p.cell(c).box;
    std::map<int, double> covered;  // by axis*2 + side
    for (CellId n : p.face_neighbours(c)) {
      const Aabb& nb = p.cell(n).box;
      const auto back = p.face_neighbours(n);
      EXPECT_NE(std::find(back.begin(), back.end(), c), back.end()) << c << " and " << n;
      for (int axis = 0; axis < 3; ++axis) {
        const double a = shared_face_area(box, nb, axis);
        if (a > 0) covered[axis * 2 + (nb.min[axis] == box.max[axis] ? 1 : 0)] += a;
      }
    }
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        const float plane = side ? box.max[axis] : box.min[axis];
        if (plane == bounds.min[axis] || plane == bounds.max[axis]) continue;
        double face = 1.0;
        for (int t = 0; t < 3; ++t)
          if (t != axis) face *= box.size()[t];
        EXPECT_NEAR(covered[axis * 2 + side], face, 1e-4 * face) << "cell " << c << " axis " << axis;
      }
  }
}

TEST(ViewCells, Grid2DCoversTheEyeRangeAndLocatesBoundariesUpwards) {
  const auto grid = make_grid_partition(region_2d({0, 0, 0}, {100, 30, 45}), 10.0f);
  EXPECT_EQ(grid->kind(), "grid");
  ASSERT_EQ(grid->cell_count(), 10u * 5u);
  EXPECT_FLOAT_EQ(grid->cell(0).box.min.y, 1.45f);
  EXPECT_FLOAT_EQ(grid->cell(0).box.max.y, 1.95f);
  EXPECT_FLOAT_EQ(grid->cell(49).box.max.z, 45.0f);  // the last row is shorter
  // A point on the face between two cells belongs to the one with the larger coordinate.
  EXPECT_EQ(grid->cell(*grid->locate({10.0f, 1.7f, 5.0f})).box.min.x, 10.0f);
  EXPECT_EQ(grid->cell(*grid->locate({100.0f, 1.7f, 45.0f})).box.max.x, 100.0f);
  EXPECT_FALSE(grid->locate({50.0f, 5.0f, 5.0f}).has_value());  // above the eye range
  EXPECT_EQ(grid->face_neighbours(0).size(), 2u);
  EXPECT_EQ(grid->face_neighbours(*grid->locate({55, 1.7f, 25})).size(), 4u);
  check_partition(*grid, covered(region_2d({0, 0, 0}, {100, 30, 45})));
}

TEST(ViewCells, Grid3DHasSixNeighboursInside) {
  CellRegion r = region_2d({0, 0, 0}, {40, 40, 40});
  r.two_d = false;
  const auto grid = make_grid_partition(r, 10.0f);
  ASSERT_EQ(grid->cell_count(), 64u);
  EXPECT_EQ(grid->face_neighbours(*grid->locate({15, 15, 15})).size(), 6u);
  check_partition(*grid, r.bounds);
}

TEST(ViewCells, OctreeFollowsVlodRules) {
  const CellRegion r = region_2d({0, 0, 0}, {80, 10, 40});
  const Vec3 hot(39.0f, 1.7f, 21.0f);
  OctreeRules rules;
  rules.root_size = 40.0f;
  rules.threshold = 100;
  rules.max_depth = 3;
  // Large sets only around one point: subdivision follows it to the maximum depth.
  const auto tree = make_octree_partition(r, rules, [&](const Aabb& b) { return b.contains(hot) ? 1000u : 10u; });
  EXPECT_EQ(tree->kind(), "octree");
  EXPECT_EQ(tree->cell(*tree->locate(hot)).depth, 3u);
  EXPECT_EQ(tree->cell_count(), 1u + 3u * 3u + 1u);  // root 0 split three times (+3 leaves each), root 1 whole
  // Across levels: the whole right root touches the small cells along x = 40.
  const auto right = *tree->locate({60, 1.7f, 20});
  EXPECT_EQ(tree->cell(right).depth, 0u);
  EXPECT_GT(tree->face_neighbours(right).size(), 2u);
  check_partition(*tree, covered(r));
  // Futility: a split that cannot halve the set is not made.
  const auto flat = make_octree_partition(r, rules, [](const Aabb&) { return 1000u; });
  EXPECT_EQ(flat->cell_count(), 2u);
  // The threshold: nothing above it, nothing split.
  rules.threshold = 5000;
  EXPECT_EQ(make_octree_partition(r, rules, [&](const Aabb& b) { return b.contains(hot) ? 1000u : 10u; })->cell_count(), 2u);
}

TEST(ViewCells, KdSplitsAtMultiplesOfTheViewcellSize) {
  const CellRegion r = region_2d({0, 0, 0}, {100, 10, 45});
  const auto kd = make_kd_partition(r, 10.0f);
  EXPECT_EQ(kd->kind(), "kd");
  ASSERT_EQ(kd->cell_count(), 50u);
  for (CellId c = 0; c < kd->cell_count(); ++c) {
    const Aabb& b = kd->cell(c).box;
    EXPECT_LE(b.size().x, 10.0f + 1e-4f);
    EXPECT_LE(b.size().z, 10.0f + 1e-4f);
    EXPECT_FLOAT_EQ(std::fmod(b.min.x, 10.0f), 0.0f);
    EXPECT_FLOAT_EQ(std::fmod(b.min.z, 10.0f), 0.0f);
  }
  check_partition(*kd, covered(r));
}

TEST(ViewCells, StoredPartitionAnswersTheSameAndRejectsDamage) {
  const CellRegion r = region_2d({0, 0, 0}, {80, 10, 40});
  OctreeRules rules;
  rules.root_size = 40.0f;
  const Vec3 hot(39.0f, 1.7f, 21.0f);
  const auto tree = make_octree_partition(r, rules, [&](const Aabb& b) { return b.contains(hot) ? 1000u : 10u; });
  const std::vector<uint8_t> bytes = serialize_partition(*tree);
  const auto back = deserialize_partition(bytes, "test");
  ASSERT_EQ(back->cell_count(), tree->cell_count());
  EXPECT_EQ(back->kind(), "octree");
  for (CellId c = 0; c < tree->cell_count(); ++c) {
    EXPECT_EQ(back->cell(c).box.min, tree->cell(c).box.min);
    EXPECT_EQ(back->face_neighbours(c), tree->face_neighbours(c));
  }
  EXPECT_EQ(back->locate(hot), tree->locate(hot));
  for (size_t cut = 0; cut < bytes.size(); cut += 7) EXPECT_THROW(deserialize_partition(std::span(bytes).first(cut), "test"), Error);
  std::vector<uint8_t> bad = bytes;
  bad[bad.size() - 12] ^= 0x40;  // the last node's cell id
  EXPECT_THROW(deserialize_partition(bad, "test"), Error);
}

TEST(ViewCells, CellsInsideAnObjectAreSolid) {
  test::TempDir dir;
  Object block;
  block.mesh = test::box_mesh(Aabb{Vec3(0.0f), Vec3(20.0f)});
  const World world(test::write_world(dir, {block}, NavGraph{}));
  const visibility::EmbreeScene scene(world);
  CellRegion r = region_2d({-10, -10, -10}, {30, 30, 30});
  r.two_d = false;
  const auto grid = make_grid_partition(r, 5.0f, [&](const Aabb& b) { return scene.box_is_solid(b); });
  int solid = 0;
  for (CellId c = 0; c < grid->cell_count(); ++c) {
    const Aabb& b = grid->cell(c).box;
    const bool inside = b.min.x >= 0 && b.max.x <= 20 && b.min.y >= 0 && b.max.y <= 20 && b.min.z >= 0 && b.max.z <= 20;
    EXPECT_EQ(grid->cell(c).solid, inside) << c;
    solid += grid->cell(c).solid;
  }
  EXPECT_EQ(solid, 64);
  EXPECT_TRUE(scene.inside(0, Vec3(10.0f)));
  EXPECT_FALSE(scene.inside(0, Vec3(25.0f)));
}

// The solid test counts crossings with closed meshes only: a cell on the −x side of one slanted
// open quad, inside its bounding box, is crossed once by every +x ray from its points, yet it
// is in open air. Brute-force oracle: a solid cell must be inside the block's box, the only
// closed object.
TEST(ViewCells, OnlyClosedGeometryMakesCellsSolid) {
  test::TempDir dir;
  Object slanted, block;
  slanted.mesh = test::quad_mesh({10, 0, 0}, {0, 20, 0}, {0, 20, 20}, {10, 0, 20});  // x + y/2 = 10
  const Aabb inside_block{Vec3(30.0f), Vec3(40.0f)};
  block.mesh = test::box_mesh(inside_block);
  block.id = 1;
  const World world(test::write_world(dir, {slanted, block}, NavGraph{}));
  const visibility::EmbreeScene scene(world);
  EXPECT_FALSE(scene.inside(0, Vec3(2, 2, 2)));
  EXPECT_FALSE(scene.box_is_solid(Aabb{Vec3(0.0f), Vec3(5.0f)}));
  CellRegion r = region_2d({0, 0, 0}, {40, 40, 40});
  r.two_d = false;
  const auto grid = make_grid_partition(r, 5.0f, [&](const Aabb& b) { return scene.box_is_solid(b); });
  int solid = 0;
  for (CellId c = 0; c < grid->cell_count(); ++c) {
    const Aabb& b = grid->cell(c).box;
    EXPECT_EQ(grid->cell(c).solid, inside_block.contains(b.min) && inside_block.contains(b.max)) << c;
    solid += grid->cell(c).solid;
  }
  EXPECT_EQ(solid, 8);
}

// A room of double-sided quads is closed and oriented but encloses nothing (winding number 0;
// each ray crosses every wall twice, at one point): none of its cells is solid.
TEST(ViewCells, NoCellOfADoubleSidedRoomIsSolid) {
  test::TempDir dir;
  Object room;
  room.mesh = test::double_sided_room_with_door();
  const World world(test::write_world(dir, {room}, NavGraph{}));
  const visibility::EmbreeScene scene(world);
  const auto grid = make_grid_partition(region_2d({0, 0, 0}, {10, 3, 10}), 2.0f,
                                        [&](const Aabb& b) { return scene.box_is_solid(b); });
  ASSERT_EQ(grid->cell_count(), 25u);
  for (CellId c = 0; c < grid->cell_count(); ++c) EXPECT_FALSE(grid->cell(c).solid) << c;
  EXPECT_FALSE(scene.inside(0, Vec3(5.1f, 1.7f, 5.2f)));
}

}  // namespace
}  // namespace cellwalk
