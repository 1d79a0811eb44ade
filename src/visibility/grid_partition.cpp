// Uniform grid of view cells, 2D at eye height or 3D: HDoV thesis §5.2 (a 64×64 grid in its
// experiments, digest 000 §3.9) and the city seeds' cells over the ground.
#include "visibility/cell_tree.hpp"

namespace cellwalk {

CellRegion default_cell_region(const Aabb& bounds, const NavGraph& nav, bool two_d) {
  CellRegion region{bounds, two_d, 1.7f - 0.25f, 1.7f + 0.25f};
  if (!nav.nodes.empty()) {
    region.eye_min = nav.nodes[0].y;
    region.eye_max = nav.nodes[0].y;
    for (const Vec3& n : nav.nodes) {
      region.eye_min = std::min(region.eye_min, n.y);
      region.eye_max = std::max(region.eye_max, n.y);
    }
    region.eye_min -= 0.25f;
    region.eye_max += 0.25f;
    // Cells cover where a viewer can go, not only the geometry: a street or a path past the
    // last object still has sets (paths run along the graph's edges, within a metre of them).
    for (const Vec3& n : nav.nodes) {
      region.bounds.min = glm::min(region.bounds.min, n - Vec3(1.0f));
      region.bounds.max = glm::max(region.bounds.max, n + Vec3(1.0f));
    }
  }
  return region;
}

std::unique_ptr<ViewCellPartition> make_grid_partition(const CellRegion& region, float cell_size,
                                                       const SolidTest& solid) {
  const visibility::RootGrid grid = visibility::root_grid(region, cell_size);
  std::vector<visibility::BoxNode> roots;
  for (int k = 0; k < grid.dims.z; ++k)
    for (int j = 0; j < grid.dims.y; ++j)
      for (int i = 0; i < grid.dims.x; ++i) {
        visibility::BoxNode node;
        node.box = grid.root_box(i, j, k);
        node.solid = solid && solid(node.box);
        roots.push_back(std::move(node));
      }
  return visibility::make_cell_tree("grid", grid, std::move(roots));
}

}  // namespace cellwalk
