// The one implementation behind every view-cell partition (grid, octree, k-d): a grid of root
// boxes, each the root of a tree whose children tile their parent. Leaves are the view cells.
// HDoV thesis §5.2 (cells), vLOD §2.1 (grid of octrees), stratified thesis §3.1.1 (k-d tree).
#pragma once

#include <glm/glm.hpp>

#include "cellwalk/visibility/view_cell.hpp"

namespace cellwalk::visibility {

// A box being built: a leaf when it has no children. Children must tile the box exactly, with
// shared faces at bit-identical coordinates (so face-neighbour tests can compare with ==).
struct BoxNode {
  Aabb box;
  uint32_t depth = 0;
  bool solid = false;
  std::vector<BoxNode> children;
};

// The roots: dims.x * dims.y * dims.z boxes, x fastest, root (i, j, k) spanning
// origin + (i, j, k) * step clamped to `bounds` (the last row may be shorter).
struct RootGrid {
  Aabb bounds;
  glm::ivec3 dims{1};
  Vec3 step{1.0f};
  Aabb root_box(int i, int j, int k) const;
};

// The roots of `region` in cubes of side `size` (one layer spanning the eye range in 2D).
RootGrid root_grid(const CellRegion& region, float size);

// Flattens roots (in RootGrid order) into a partition; leaf cell ids follow depth-first order.
std::unique_ptr<ViewCellPartition> make_cell_tree(std::string kind, const RootGrid& grid,
                                                  std::vector<BoxNode> roots);

// The children of `box` split at its centre along the chosen axes (4 in 2D, 8 in 3D, 2 for one
// axis), in x-fastest order.
std::vector<Aabb> split_box(const Aabb& box, bool x, bool y, bool z, const Vec3& at);

}  // namespace cellwalk::visibility
