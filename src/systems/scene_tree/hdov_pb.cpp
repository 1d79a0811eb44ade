// HDoV thesis §6.1.2 and Fig. 6.2 (digest 000 §3.13): the Polygon Budget traversal of the memory
// HDoV scene tree, with view frustum culling. The figure leaves gaps; resolved here as
// docs/scene-tree.md, "PB", explains:
//  - B(c_i) = B · d_i / D · k with k = remaining / I is each child's own budget, D the DoV of
//    the children refined (those visible and meeting the frustum: culled ones get no share); it caps the
//    child's level (ComputeLodBudget: LOD = min(λ·highest + (1 − λ)·lowest, B_i), snapped to
//    the finest level within it). Whether a node can be drawn at all is decided against the
//    global remaining budget, as in the figure.
//  - Refine returns whether its whole subtree was drawn. A leaf whose level does not fit the
//    remaining budget is dropped and fails.
//  - A failed internal node tries its own LOD in place of its subtree: the subtree's selections
//    are taken back and their triangles refunded first. If the LOD does not fit either, the
//    subtree's partial selection stays (it is within budget) and the node fails upwards.
//  - MAX_ATTEMPTS counts consecutive failed fallbacks (reset by a successful one); past it the
//    traversal stops and what is selected is drawn. The figure then draws the node's LOD even
//    over budget (the overshoot near its frame 160); here nothing is, so the budget is a hard
//    upper bound.
#include <algorithm>

#include "cellwalk/systems/scene_tree/scene_tree.hpp"
#include "cellwalk/lod/dov_level.hpp"

namespace cellwalk {
namespace {

class PolygonBudget {
 public:
  PolygonBudget(const SceneTree& tree, const SceneTreeVisibility& vd, const Frustum& frustum, const PbParams& params,
                std::vector<TreeSelection>& out, TraversalStats& stats)
      : tree_(tree), vd_(vd), frustum_(frustum), params_(params), out_(out), stats_(stats),
        remaining_(double(params.budget)) {}

  // REQUIRES: n is visible (DoV > 0) and not outside the frustum (`c` is its containment).
  bool refine(NodeIndex n, double budget, Containment c) {
    if (stats_.aborted) return true;
    const double dov = vd_[n].dov;
    const SceneTreeNode& node = tree_.node(n);
    if (node.is_leaf()) return draw(n, level_within(n, dov, budget));

    // The children refined: visible and meeting the frustum, in descending DoV. The rest get
    // no share (they are culled), so the node's budget goes to what can be drawn.
    std::pair<NodeIndex, Containment> order[2];
    size_t count = 0;
    double shared_dov = 0.0;
    for (NodeIndex child : node.child) {
      ++stats_.nodes_visited;
      if (!(vd_[child].dov > 0.0f)) continue;
      const Containment cc = c == Containment::kInside ? c : frustum_.classify(tree_.node(child).box);
      if (cc == Containment::kOutside) continue;
      order[count++] = {child, cc};
      shared_dov += vd_[child].dov;
    }
    if (count == 2 && vd_[order[1].first].dov > vd_[order[0].first].dov) std::swap(order[0], order[1]);
    const size_t mark = out_.size();
    const double remaining_before = remaining_;
    bool success = true;
    for (size_t i = 0; i < count; ++i) {
      const auto [child, cc] = order[i];
      const double share = budget * (double(vd_[child].dov) / shared_dov) * (remaining_ / double(params_.budget));
      success = refine(child, share, cc) && success;
    }
    if (success || stats_.aborted) return true;
    return fall_back(n, dov, budget, mark, remaining_before);
  }

 private:
  // ComputeLodBudget: λ-interpolated triangle target capped by the node's budget.
  uint32_t level_within(NodeIndex n, double dov, double budget) const {
    const double lambda = params_.dov_levels ? dov_weight(dov, params_.max_dov) : 1.0;
    const double finest = tree_.triangles(n, 0);
    const double coarsest = tree_.triangles(n, tree_.node(n).level_count - 1);
    return finest_level_within(tree_, n, std::min(dov_triangle_target(lambda, finest, coarsest), budget));
  }

  bool draw(NodeIndex n, uint32_t level) {
    const double t = tree_.triangles(n, level);
    if (t > remaining_) return false;
    out_.push_back({n, level});
    remaining_ -= t;
    return true;
  }

  // The node's own LOD instead of its subtree's partial selection (refunded first).
  bool fall_back(NodeIndex n, double dov, double budget, size_t mark, double remaining_before) {
    if (tree_.node(n).level_count > 0) {
      const uint32_t level = level_within(n, dov, budget);
      if (tree_.triangles(n, level) <= remaining_before) {
        out_.resize(mark);
        remaining_ = remaining_before;
        draw(n, level);
        attempts_ = 0;
        return true;
      }
    }
    if (++attempts_ > params_.max_attempts) stats_.aborted = true;
    return false;
  }

  const SceneTree& tree_;
  const SceneTreeVisibility& vd_;
  const Frustum& frustum_;
  const PbParams& params_;
  std::vector<TreeSelection>& out_;
  TraversalStats& stats_;
  double remaining_;
  uint32_t attempts_ = 0;
};

}  // namespace

void pb_traverse(const SceneTree& tree, const SceneTreeVisibility& vd, const Frustum& frustum,
                 const PbParams& params, std::vector<TreeSelection>& out, TraversalStats& stats) {
  out.clear();
  stats = {};
  ++stats.nodes_visited;
  const Containment root = frustum.classify(tree.node(0).box);
  if (vd[0].dov > 0.0f && root != Containment::kOutside)
    PolygonBudget(tree, vd, frustum, params, out, stats).refine(0, double(params.budget), root);
  count_selection(tree, out, stats);
}

}  // namespace cellwalk
