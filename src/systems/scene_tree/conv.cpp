// HDoV thesis §6.3 (digest 000 §5.6): CONV, the conventional renderer the memory HDoV scene tree
// is measured against — hierarchical view frustum culling over the same k-d subdivision, every
// object that survives drawn at full detail.
#include "cellwalk/systems/scene_tree/scene_tree.hpp"

namespace cellwalk {

void conv_traverse(const SceneTree& tree, const Frustum& frustum, std::vector<TreeSelection>& out,
                   TraversalStats& stats) {
  out.clear();
  stats = {};
  // (node, whether an ancestor lies wholly inside the frustum: then no test is needed)
  std::vector<std::pair<NodeIndex, bool>> stack{{0, false}};
  while (!stack.empty()) {
    const auto [n, inside] = stack.back();
    stack.pop_back();
    ++stats.nodes_visited;
    const SceneTreeNode& node = tree.node(n);
    const Containment c = inside ? Containment::kInside : frustum.classify(node.box);
    if (c == Containment::kOutside) continue;
    if (node.is_leaf()) {
      out.push_back({n, 0});
      continue;
    }
    stack.push_back({node.child[1], c == Containment::kInside});
    stack.push_back({node.child[0], c == Containment::kInside});
  }
  count_selection(tree, out, stats);
}

}  // namespace cellwalk
