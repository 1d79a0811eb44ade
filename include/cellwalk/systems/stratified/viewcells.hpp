// Stratified rendering (seed 002, Xiong 1996) §2.1, §3.1.1, §3.1.3 (digest 002 §3.1, §3.5): the
// viewcells (leaves of a k-d tree split at multiples of v), their bounding boxes (cubes of side
// b centred at the cell centre C) and their near lists (every object whose box intersects the
// cell's bounding box), built depth first so that the lists held at once stay O(h·j).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "cellwalk/core/geometry.hpp"
#include "cellwalk/scene/scene.hpp"
#include "cellwalk/visibility/view_cell.hpp"

namespace cellwalk::stratified {

// The bounding box of a viewcell (§2.1): the cube of side b centred at the cell's centre C, the
// original viewpoint the far field is drawn from.
Aabb bounding_box(const ViewCell& cell, float b);

// `region` with its split axes (x and z, and y in 3D) grown at the far side to whole multiples
// of v, so every viewcell is exactly v long along them (the thesis's cubes; in 2D the cells span
// the region's eye-height range in y, which the bounds take). Then the union of a k-d cell's leaves' bounding boxes is
// the cell inflated by (b − v)/2, the thesis's object boundary.
CellRegion viewcell_region(CellRegion region, float v);

// Near lists by cell, in one array: near(c) is the ascending object ids of cell c.
struct NearLists {
  std::vector<uint64_t> offsets;  // cell_count + 1
  std::vector<ObjectId> ids;
  std::span<const ObjectId> near(CellId cell) const {
    return {ids.data() + offsets.at(cell), ids.data() + offsets.at(cell + 1)};
  }
};

struct Viewcells {
  std::unique_ptr<ViewCellPartition> partition;  // kind "kd"
  NearLists near;
  float v = 0, b = 0;
  uint32_t height = 0;           // of the k-d tree: its longest root-to-leaf path, in edges
  uint64_t peak_held_ids = 0;    // the most ids the build's working lists held at once (§3.1.3)
};

// Builds the k-d viewcells over viewcell_region(region, v) and their near lists: a k-d cell
// keeps the objects of its parent's list that intersect its object boundary (FindNearObj), the
// parent's list is freed once both children's exist, and a leaf's list is its near list.
// Intersect is the conservative box test [ours, digest §3.5]: a false "near" costs time, never
// image quality. Throws Error unless 0 < v < b, or when the cells would exceed kMaxGridCells
// (make_kd_partition's root grid check).
Viewcells build_viewcells(const CellRegion& region, float v, float b, std::span<const Aabb> object_bounds);

}  // namespace cellwalk::stratified
