// k-d tree of view cells after the stratified thesis §3.1.1 (digest 002 §3.5): one root over
// the region, halved "near the middle" at integer multiples of the viewcell size v, so leaves
// align to a v-grid and the tree stays balanced. The axis is the longest one ([ours]; the
// thesis leaves it open), never y in 2D.
#include <cmath>

#include "cellwalk/core/error.hpp"
#include "visibility/cell_tree.hpp"

namespace cellwalk {

namespace {

// The split coordinate of box along axis a: the multiple of v (from the region's origin) nearest
// the middle, strictly inside the box; NaN when the box is no longer than v along a.
float split_at(const Aabb& box, int a, float origin, float v) {
  if (box.max[a] - box.min[a] <= v * (1.0f + 1e-4f)) return NAN;
  const float k = std::round((box.center()[a] - origin) / v);
  float at = origin + k * v;
  if (at <= box.min[a]) at = origin + (k + 1) * v;
  if (at >= box.max[a]) at = origin + (k - 1) * v;
  return at > box.min[a] && at < box.max[a] ? at : NAN;
}

void split(visibility::BoxNode& node, const Vec3& origin, float v, bool two_d, const SolidTest& solid) {
  node.solid = solid && solid(node.box);
  if (node.solid) return;
  const std::optional<std::array<Aabb, 2>> halves = kd_split(node.box, origin, v, two_d);
  if (!halves) return;
  for (const Aabb& box : *halves) {
    visibility::BoxNode child;
    child.box = box;
    child.depth = node.depth + 1;
    split(child, origin, v, two_d, solid);
    node.children.push_back(std::move(child));
  }
}

}  // namespace

std::optional<std::array<Aabb, 2>> kd_split(const Aabb& box, const Vec3& origin, float v, bool two_d) {
  int axis = -1;
  for (int a = 0; a < 3; ++a) {
    if (two_d && a == 1) continue;
    if (std::isnan(split_at(box, a, origin[a], v))) continue;
    if (axis < 0 || box.size()[a] > box.size()[axis]) axis = a;
  }
  if (axis < 0) return std::nullopt;
  std::array<Aabb, 2> halves{box, box};
  halves[0].max[axis] = halves[1].min[axis] = split_at(box, axis, origin[axis], v);
  return halves;
}

std::unique_ptr<ViewCellPartition> make_kd_partition(const CellRegion& region, float viewcell_size,
                                                     const SolidTest& solid) {
  if (!(viewcell_size > 0.0f)) fail("view cells", "the viewcell size must be positive");
  visibility::RootGrid grid = visibility::root_grid(region, viewcell_size);
  grid.dims = glm::ivec3(1);
  grid.step = glm::max(grid.bounds.size(), Vec3(1e-6f));
  visibility::BoxNode root;
  root.box = grid.bounds;
  split(root, grid.bounds.min, viewcell_size, region.two_d, solid);
  std::vector<visibility::BoxNode> roots;
  roots.push_back(std::move(root));
  return visibility::make_cell_tree("kd", grid, std::move(roots));
}

}  // namespace cellwalk
