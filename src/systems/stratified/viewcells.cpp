// Stratified thesis §2.1, §3.1.1 (FindNearObj, Figs. 3-2 and 3-4) and §3.1.3 (depth-first build
// in O(h·j) memory); digest 002 §3.5.
#include "cellwalk/systems/stratified/viewcells.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "cellwalk/core/error.hpp"

namespace cellwalk::stratified {
namespace {

// The object boundary of a k-d cell: the union of its leaves' bounding boxes, which (leaves
// exactly v along split axes, viewcell_region) is the cell inflated by (b − leaf extent)/2 per
// axis. A hair wider, so float rounding can only keep an object a level longer, never drop one a
// leaf's exact test would keep.
Aabb object_boundary(const Aabb& cell, float v, float b) {
  Aabb boundary = cell;
  for (int a = 0; a < 3; ++a) {
    const float leaf = std::min(v, cell.max[a] - cell.min[a]);
    const float grow = 0.5f * (b - leaf) + 1e-4f * b;
    boundary.min[a] -= grow;
    boundary.max[a] += grow;
  }
  return boundary;
}

// FindNearObj: the objects of `parent` whose box intersects `boundary`.
std::vector<ObjectId> find_near_objects(const Aabb& boundary, std::span<const ObjectId> parent,
                                        std::span<const Aabb> object_bounds) {
  std::vector<ObjectId> near;
  for (const ObjectId id : parent)
    if (object_bounds[id].overlaps(boundary)) near.push_back(id);
  return near;
}

struct Builder {
  const ViewCellPartition& partition;
  Vec3 origin;
  float v, b;
  bool two_d;
  std::span<const Aabb> object_bounds;
  std::vector<std::vector<ObjectId>> leaf_lists;  // by cell id
  uint64_t held = 0, peak_held = 0;
  uint32_t height = 0;

  // REQUIRES: `list` holds the objects of the parent's list inside this cell's object boundary;
  // `held` counts it.
  void descend(const Aabb& cell, std::vector<ObjectId> list, uint32_t depth) {
    height = std::max(height, depth);
    const auto halves = kd_split(cell, origin, v, two_d);
    if (!halves) {
      const std::optional<CellId> id = partition.locate(cell.center());
      if (!id) fail("stratify", "internal: a k-d leaf is not a cell of its partition");
      // At a leaf the object boundary is the bounding box: the exact test.
      std::vector<ObjectId> near = find_near_objects(bounding_box(partition.cell(*id), b), list, object_bounds);
      held -= list.size();
      leaf_lists[*id] = std::move(near);
      return;
    }
    std::vector<ObjectId> lower = find_near_objects(object_boundary((*halves)[0], v, b), list, object_bounds);
    std::vector<ObjectId> upper = find_near_objects(object_boundary((*halves)[1], v, b), list, object_bounds);
    held += lower.size() + upper.size();
    peak_held = std::max(peak_held, held);
    held -= list.size();
    std::vector<ObjectId>().swap(list);  // both children's lists exist: free the parent's
    descend((*halves)[0], std::move(lower), depth + 1);
    descend((*halves)[1], std::move(upper), depth + 1);
  }
};

}  // namespace

Aabb bounding_box(const ViewCell& cell, float b) {
  const Vec3 c = cell.box.center();
  return {c - Vec3(0.5f * b), c + Vec3(0.5f * b)};
}

CellRegion viewcell_region(CellRegion region, float v) {
  if (region.two_d) {
    region.bounds.min.y = region.eye_min;
    region.bounds.max.y = region.eye_max;
  }
  for (int a = 0; a < 3; ++a) {
    if (region.two_d && a == 1) continue;
    const float extent = region.bounds.max[a] - region.bounds.min[a];
    region.bounds.max[a] = region.bounds.min[a] + std::max(1.0f, std::ceil(extent / v - 1e-4f)) * v;
  }
  return region;
}

Viewcells build_viewcells(const CellRegion& region, float v, float b, std::span<const Aabb> object_bounds) {
  if (!(v > 0 && b > v && std::isfinite(b)))
    fail("stratify", "the viewcell side v and the box side b must satisfy 0 < v < b");
  const CellRegion cells = viewcell_region(region, v);
  Viewcells out;
  out.v = v;
  out.b = b;
  out.partition = make_kd_partition(cells, v);
  Builder builder{*out.partition, cells.bounds.min, v, b, cells.two_d, object_bounds, {}, 0, 0, 0};
  builder.leaf_lists.resize(out.partition->cell_count());
  std::vector<ObjectId> all(object_bounds.size());
  for (ObjectId id = 0; id < all.size(); ++id) all[id] = id;
  const Aabb root = cells.bounds;
  std::vector<ObjectId> root_list = find_near_objects(object_boundary(root, v, b), all, object_bounds);
  std::vector<ObjectId>().swap(all);
  builder.held = builder.peak_held = root_list.size();
  builder.descend(root, std::move(root_list), 0);
  out.height = builder.height;
  out.peak_held_ids = builder.peak_held;
  out.near.offsets.push_back(0);
  for (std::vector<ObjectId>& list : builder.leaf_lists) {
    out.near.ids.insert(out.near.ids.end(), list.begin(), list.end());
    out.near.offsets.push_back(out.near.ids.size());
    std::vector<ObjectId>().swap(list);
  }
  return out;
}

}  // namespace cellwalk::stratified
