// HDoV thesis Fig. 5.13 (digest §2.3): the HDoV-tree of a world from the DoVs its view cells
// stored (`cellwalk pvs --engine dov`), the glue between the visibility layer and the tree.
#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/visual/visual_strategy.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"

namespace cellwalk {

HdovTreeBuild build_visual_tree(const World& world, const std::string& path, const HdovBuildParams& params,
                                const std::function<void(uint64_t, uint64_t)>& progress) {
  if (!world.file().has_section(visibility::kDovSection))
    fail(world.file().path(), "has no stored DoVs for the HDoV-tree: run `cellwalk pvs " + world.file().path() +
                                  " --engine dov --cells grid:SIZE` first");
  const visibility::StoredPvs stored(world);
  HdovTreeBuild tree = build_hdov_tree(world, stored.partition(), [&](CellId c) { return stored.set(c); }, params, progress);
  write_hdov_tree(tree, path);
  return tree;
}

}  // namespace cellwalk
