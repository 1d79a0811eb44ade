// HDoV thesis §6.1.1 (digest 000 §3.12): Visibility Simplification Culling, the threshold search
// of §5.3 (Fig. 5.4, digest §3.8) run on the memory scene tree with view frustum culling.
//  - DoV = 0: the node is skipped and the search goes on with the next (`continue`, the
//    digest's fix of the figure's `return`).
//  - An internal node stops the descent when DoV <= η and eq. 5.3 holds: its LOD costs less
//    than its NVO visible leaves. With the per-node values the tree measures, m·f·s^h is the
//    node's finest LOD's triangles and f the mean level-0 triangles of its m leaves, so eq.
//    5.3 reads finest · m < Σ leaf triangles · NVO (eq. 5.4 is its logarithm, base M = 2).
//  - Levels: eq. 5.5 for a stopped internal node, eq. 5.6 for a leaf, both read as triangle
//    targets and snapped to the nearest stored level.
#include <algorithm>

#include "cellwalk/lod/dov_level.hpp"
#include "cellwalk/systems/scene_tree/scene_tree.hpp"

namespace cellwalk {
namespace {

// Eq. 5.5 / 5.6: k · LOD_highest + (1 − k) · LOD_lowest as a triangle target, k in [0, 1].
uint32_t interpolated_level(const SceneTree& tree, NodeIndex n, double k) {
  const double finest = tree.triangles(n, 0);
  const double coarsest = tree.triangles(n, tree.node(n).level_count - 1);
  return nearest_level(tree, n, dov_triangle_target(k, finest, coarsest));
}

// Eq. 5.3 with the node's measured values (see the file comment).
bool internal_lod_is_cheaper(const SceneTree& tree, NodeIndex n, uint32_t nvo) {
  const SceneTreeNode& node = tree.node(n);
  return double(tree.triangles(n, 0)) * node.leaf_count < double(node.leaf_triangles) * nvo;
}

class Vsc {
 public:
  Vsc(const SceneTree& tree, const SceneTreeVisibility& vd, const Frustum& frustum, const VscParams& params,
      std::vector<TreeSelection>& out, TraversalStats& stats)
      : tree_(tree), vd_(vd), frustum_(frustum), params_(params), out_(out), stats_(stats) {}

  void search(NodeIndex n, bool inside) {
    ++stats_.nodes_visited;
    const VisibilityDatum& d = vd_[n];
    if (!(d.dov > 0.0f)) return;
    const SceneTreeNode& node = tree_.node(n);
    const Containment c = inside ? Containment::kInside : frustum_.classify(node.box);
    if (c == Containment::kOutside) return;
    if (node.is_leaf()) {
      const double k = dov_weight(d.dov, params_.max_dov);
      out_.push_back({n, params_.dov_leaf_levels ? interpolated_level(tree_, n, k) : 0u});
      return;
    }
    if (d.dov <= params_.eta && node.level_count > 0 && internal_lod_is_cheaper(tree_, n, d.nvo)) {
      out_.push_back({n, interpolated_level(tree_, n, double(d.dov) / params_.eta)});  // η > 0 here
      return;
    }
    search(node.child[0], c == Containment::kInside);
    search(node.child[1], c == Containment::kInside);
  }

 private:
  const SceneTree& tree_;
  const SceneTreeVisibility& vd_;
  const Frustum& frustum_;
  const VscParams& params_;
  std::vector<TreeSelection>& out_;
  TraversalStats& stats_;
};

}  // namespace

void vsc_traverse(const SceneTree& tree, const SceneTreeVisibility& vd, const Frustum& frustum,
                  const VscParams& params, std::vector<TreeSelection>& out, TraversalStats& stats) {
  out.clear();
  stats = {};
  Vsc(tree, vd, frustum, params, out, stats).search(0, false);
  count_selection(tree, out, stats);
}

}  // namespace cellwalk
