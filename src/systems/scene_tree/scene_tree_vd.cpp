// HDoV thesis §6.2.2 (digest 000 §2.3, run time of the memory tree): on a change of view cell the
// leaves' VD = (DoV, NVO) are loaded for the new cell through the node-id hash and the internal
// nodes' recomputed bottom-up as sums of their children's. Only the root paths of the old and
// new visible leaves are touched, so a cell change costs O(visible · depth), not O(nodes).
#include <algorithm>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/scene_tree/scene_tree.hpp"

namespace cellwalk {

SceneTreeVisibility::SceneTreeVisibility(const SceneTree& tree) : tree_(tree), vd_(tree.nodes().size()) {
  touched_.reserve(vd_.size());  // its most: resident_bytes() stays the same after assign()
}

void SceneTreeVisibility::assign(const VisibleSet& set) {
  if (set.dov.size() != set.objects.size())
    fail("HDoV scene tree", "the view cell's visible set has no DoVs (compute it with the dov engine)");
  for (NodeIndex n : touched_) vd_[n] = {};
  touched_.clear();
  for (size_t i = 0; i < set.objects.size(); ++i) {
    if (!(set.dov[i] > 0.0f)) continue;  // DoV 0: invisible, as if absent
    const NodeIndex leaf = tree_.leaf_of(set.objects[i]);
    if (leaf == kNoNode) fail("HDoV scene tree", "visible object " + std::to_string(set.objects[i]) + " is not in the tree");
    if (vd_[leaf].nvo != 0) continue;  // listed twice
    vd_[leaf] = {set.dov[i], 1};
    // Ancestors are collected once each: the walk up stops at one already collected (its VD
    // is still zero until the sums below, so a non-zero NVO marks "collected").
    touched_.push_back(leaf);
    for (NodeIndex n = tree_.node(leaf).parent; n != kNoNode && vd_[n].nvo == 0; n = tree_.node(n).parent) {
      vd_[n].nvo = 1;
      touched_.push_back(n);
    }
  }
  std::sort(touched_.begin(), touched_.end());
  // Descending index: children (larger indices) are final before their parent sums them.
  for (auto it = touched_.rbegin(); it != touched_.rend(); ++it) {
    const SceneTreeNode& node = tree_.node(*it);
    if (node.is_leaf()) continue;
    const VisibilityDatum& a = vd_[node.child[0]];
    const VisibilityDatum& b = vd_[node.child[1]];
    vd_[*it] = {a.dov + b.dov, a.nvo + b.nvo};
  }
}

uint64_t SceneTreeVisibility::resident_bytes() const {
  return vd_.capacity() * sizeof(VisibilityDatum) + touched_.capacity() * sizeof(NodeIndex) + sizeof(*this);
}

}  // namespace cellwalk
