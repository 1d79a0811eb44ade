// Adaptive octree of view cells after vLOD §2.1 and §6 (digest 001 §3.1): a uniform grid whose
// cells are octree roots, subdivided while the visible set is too large, with the 2× futility
// rule and a maximum depth. In 2D the tree splits x and z only (a quadtree at eye height).
#include <tbb/parallel_for.h>

#include "visibility/cell_tree.hpp"

namespace cellwalk {

namespace {

struct OctreeBuild {
  const OctreeRules& rules;
  const CellSetSize& set_size;
  const SolidTest& solid;
  bool two_d;

  // Subdivides `node` (whose own set size is `size`) as far as the rules allow. The children's
  // sizes must be known before deciding, because the futility rule compares against them.
  void refine(visibility::BoxNode& node, uint64_t size) const {
    if (node.solid || size <= rules.threshold || node.depth >= rules.max_depth) return;
    std::vector<visibility::BoxNode> children;
    std::vector<uint64_t> sizes;
    uint64_t smallest = UINT64_MAX;
    for (const Aabb& box : visibility::split_box(node.box, true, !two_d, true, node.box.center())) {
      visibility::BoxNode child;
      child.box = box;
      child.depth = node.depth + 1;
      child.solid = solid && solid(box);
      sizes.push_back(child.solid ? 0 : set_size(box));
      if (!child.solid) smallest = std::min(smallest, sizes.back());
      children.push_back(std::move(child));
    }
    // Futility: splitting cannot even halve the smallest child's set, so it is not worth it.
    if (smallest == UINT64_MAX || size <= 2 * smallest) return;
    for (size_t i = 0; i < children.size(); ++i) refine(children[i], sizes[i]);
    node.children = std::move(children);
  }
};

}  // namespace

std::unique_ptr<ViewCellPartition> make_octree_partition(const CellRegion& region,
                                                         const OctreeRules& rules,
                                                         const CellSetSize& set_size,
                                                         const SolidTest& solid) {
  const visibility::RootGrid grid = visibility::root_grid(region, rules.root_size);
  std::vector<visibility::BoxNode> roots(size_t(grid.dims.x) * grid.dims.y * grid.dims.z);
  const OctreeBuild build{rules, set_size, solid, region.two_d};
  // Roots are independent; each is refined on one thread, so the result does not depend on
  // scheduling.
  tbb::parallel_for(size_t(0), roots.size(), [&](size_t r) {
    const int i = int(r % grid.dims.x), j = int(r / grid.dims.x % grid.dims.y),
              k = int(r / (size_t(grid.dims.x) * grid.dims.y));
    visibility::BoxNode& node = roots[r];
    node.box = grid.root_box(i, j, k);
    node.solid = solid && solid(node.box);
    if (!node.solid) build.refine(node, set_size(node.box));
  });
  return visibility::make_cell_tree("octree", grid, std::move(roots));
}

}  // namespace cellwalk
