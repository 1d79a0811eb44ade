// Stratified viewcells and near lists (seed 002 §3.1.1, §3.1.3): the near lists the depth-first
// k-d build finds are checked against the brute-force oracle, every object against every
// cell's bounding box.
#include <random>

#include <gtest/gtest.h>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/stratified/viewcells.hpp"

namespace cellwalk::stratified {
namespace {

std::vector<Aabb> random_boxes(size_t count, float extent, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> at(-0.1f * extent, 1.1f * extent), size(0.5f, 0.08f * extent);
  std::vector<Aabb> boxes(count);
  for (Aabb& box : boxes) {
    box.min = Vec3(at(rng), 0.0f, at(rng));
    box.max = box.min + Vec3(size(rng), size(rng), size(rng));
  }
  return boxes;
}

std::vector<ObjectId> brute_near(const Aabb& box, const std::vector<Aabb>& objects) {
  std::vector<ObjectId> near;
  for (ObjectId id = 0; id < objects.size(); ++id)
    if (objects[id].overlaps(box)) near.push_back(id);
  return near;
}

CellRegion region_2d(float extent) {
  CellRegion region;
  region.bounds = {Vec3(0.0f), Vec3(extent, 30.0f, extent * 0.7f)};
  return region;
}

TEST(StratifiedViewcells, NearListsAreEveryObjectMeetingTheBoundingBox) {
  for (const uint32_t seed : {1u, 2u, 3u}) {
    const std::vector<Aabb> objects = random_boxes(400, 200.0f, seed);
    const Viewcells cells = build_viewcells(region_2d(200.0f), 7.0f, 41.0f, objects);
    ASSERT_GT(cells.partition->cell_count(), 100u);
    for (CellId c = 0; c < cells.partition->cell_count(); ++c) {
      const std::span<const ObjectId> near = cells.near.near(c);
      EXPECT_EQ(std::vector<ObjectId>(near.begin(), near.end()),
                brute_near(bounding_box(cells.partition->cell(c), 41.0f), objects))
          << "cell " << c << " seed " << seed;
    }
  }
}

TEST(StratifiedViewcells, CellsAreCubesOfSideVOnTheGrid) {
  const Viewcells cells = build_viewcells(region_2d(100.0f), 7.0f, 30.0f, random_boxes(10, 100.0f, 1));
  // 100 m → 15 cells of 7 m (105 m), 70 m → 10 cells.
  EXPECT_EQ(cells.partition->cell_count(), 150u);
  for (CellId c = 0; c < cells.partition->cell_count(); ++c) {
    const Aabb& box = cells.partition->cell(c).box;
    EXPECT_NEAR(box.size().x, 7.0f, 1e-3f);
    EXPECT_NEAR(box.size().z, 7.0f, 1e-3f);
    EXPECT_NEAR(std::fmod(box.min.x, 7.0f) < 3.5f ? std::fmod(box.min.x, 7.0f) : 7.0f - std::fmod(box.min.x, 7.0f), 0.0f, 1e-3f);
    // 2D: the eye-height range; the bounding box is a cube of side b around the centre.
    EXPECT_FLOAT_EQ(box.min.y, 1.45f);
    const Aabb bounds = bounding_box(cells.partition->cell(c), 30.0f);
    EXPECT_NEAR(bounds.size().y, 30.0f, 1e-4f);
    EXPECT_NEAR(bounds.center().x, box.center().x, 1e-4f);
  }
}

TEST(StratifiedViewcells, ThreeDimensionalCellsAlsoSplitInY) {
  CellRegion region = region_2d(60.0f);
  region.two_d = false;
  const std::vector<Aabb> objects = random_boxes(150, 60.0f, 7);
  const Viewcells cells = build_viewcells(region, 10.0f, 25.0f, objects);
  EXPECT_EQ(cells.partition->cell_count(), 6u * 3u * 5u);
  for (CellId c = 0; c < cells.partition->cell_count(); ++c) {
    const std::span<const ObjectId> near = cells.near.near(c);
    EXPECT_EQ(std::vector<ObjectId>(near.begin(), near.end()), brute_near(bounding_box(cells.partition->cell(c), 25.0f), objects));
  }
}

TEST(StratifiedViewcells, WorkingListsStayWithinHeightTimesObjects) {
  // §3.1.3: O(h·j): the pending siblings' lists along one root-to-leaf path, at most j each.
  const std::vector<Aabb> objects = random_boxes(2000, 400.0f, 11);
  const Viewcells cells = build_viewcells(region_2d(400.0f), 5.0f, 30.0f, objects);
  EXPECT_GT(cells.height, 10u);
  EXPECT_LE(cells.peak_held_ids, uint64_t(cells.height + 1) * objects.size());
  // And far less than keeping every k-d cell's list would: Σ over leaves alone.
  EXPECT_LT(cells.peak_held_ids, cells.near.ids.size());
}

TEST(StratifiedViewcells, BadSidesAreRefused) {
  const std::vector<Aabb> objects = random_boxes(5, 50.0f, 1);
  EXPECT_THROW(build_viewcells(region_2d(50.0f), 10.0f, 10.0f, objects), Error);
  EXPECT_THROW(build_viewcells(region_2d(50.0f), 0.0f, 10.0f, objects), Error);
  EXPECT_THROW(build_viewcells(region_2d(50.0f), NAN, 10.0f, objects), Error);
  EXPECT_THROW(build_viewcells(region_2d(1e6f), 0.1f, 10.0f, objects), Error);  // 10^14 cells
}

}  // namespace
}  // namespace cellwalk::stratified
