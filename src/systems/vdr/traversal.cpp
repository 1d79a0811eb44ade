// Seed 004 (Zheng): §3.4 the run-time view tests, §4.3 MANAGE-TRAVERSAL (Fig. 4.6) and §4.4 the
// priority (Fig. 4.7), linear (Fig. 4.8) and constant-time (Fig. 4.9) traversals.
#include "cellwalk/systems/vdr/traversal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <utility>

#include "cellwalk/core/error.hpp"

namespace cellwalk::vdr {

namespace {
constexpr uint8_t kInS = 1, kInC = 2;
constexpr float kMustSplit = std::numeric_limits<float>::max();
}  // namespace

std::string traversal_name(TraversalKind kind) {
  switch (kind) {
    case TraversalKind::kPriority: return "priority";
    case TraversalKind::kLinear: return "linear";
    case TraversalKind::kConstant: return "constant";
  }
  return "?";
}

TraversalKind parse_traversal(const std::string& word) {
  for (TraversalKind k : {TraversalKind::kPriority, TraversalKind::kLinear, TraversalKind::kConstant})
    if (traversal_name(k) == word) return k;
  fail("--traversal", "unknown traversal '" + word + "': use priority, linear or constant");
}

uint32_t op_wire_bytes(const ProgressiveMesh& pm, const Op& op) {
  const uint32_t adjusted = 4 * static_cast<uint32_t>(pm.adjusted_of(op.node).size());
  return op.split ? 43 + adjusted : 11 + adjusted;
}

// The frame's view cone, prepared once: cos α and sin α for the out-of-view test without trig
// per node, and the threshold's factor 2 τ tan α.
struct Traversal::View {
  Vec3 eye, dir;
  float cos_a, sin_a, threshold_per_depth;
};


Traversal::Traversal(const VdrModel& model, TraversalKind kind, ErrorUnits units)
    : model_(model), kind_(kind), units_(units), cut_(model.dag), queued_(model.dag.node_count(), 0),
      triangles_(model.pm.base_triangle_count) {
  for (uint32_t i = 0; i < model.dag.node_count(); ++i)
    if (cut_.can_split(i)) fs_.push_back(i), queued_[i] = kInS;  // F_s = the roots
}

float Traversal::need(uint32_t i, const ViewParams& vp) const {
  const Vec3 dir = glm::normalize(vp.aim - vp.eye);
  return need(i, View{vp.eye, dir, std::cos(vp.alpha), std::sin(vp.alpha), 2 * vp.tau * std::tan(vp.alpha)});
}

float Traversal::need(uint32_t i, const View& v) const {
  const ProgressiveMesh& pm = model_.pm;
  const NodeAttributes& a = model_.dag.attributes;
  const Vec3 to = pm.positions[pm.v_c(i)] - v.eye;
  const float dist = glm::length(to);
  if (dist <= a.rad[i]) return kMustSplit;  // the eye is inside the node's sphere
  // Out of view: γ − φ > α ⇔ cos γ < cos(α + φ), when α + φ < π.
  const float sin_phi = a.rad[i] / dist, cos_phi = std::sqrt(1 - sin_phi * sin_phi);
  const float cos_gamma = glm::dot(to, v.dir) / dist;
  const float cos_sum = v.cos_a * cos_phi - v.sin_a * sin_phi;
  const bool sum_below_pi = v.sin_a * cos_phi + v.cos_a * sin_phi > 0 || cos_sum > 0;
  if (sum_below_pi && cos_gamma < cos_sum) return 0;
  // Back-facing (Eq. 3.4.1): the whole normal cone faces away.
  if (a.cone_sin[i] < 1 && glm::dot(to, pm.normals[pm.v_c(i)]) / dist > a.cone_sin[i]) return 0;
  const float depth = glm::dot(to, v.dir);
  if (depth <= 0) return kMustSplit;  // in view only through its sphere: beside the eye
  const float error = units_ == ErrorUnits::kLength ? std::sqrt(a.ap_err[i]) : a.ap_err[i];
  return error / (v.threshold_per_depth * depth);
}

uint32_t Traversal::triangle_delta(uint32_t node) const {
  return (model_.pm.v_l[node] != kNone) + (model_.pm.v_r[node] != kNone);
}

void Traversal::enqueue(const std::vector<uint32_t>& nodes, bool collapse_front) {
  const uint8_t bit = collapse_front ? kInC : kInS;
  for (uint32_t n : nodes)
    if (!(queued_[n] & bit)) {
      queued_[n] |= bit;
      (collapse_front ? fc_ : fs_).push_back(n);
    }
}

bool Traversal::apply(uint32_t node, bool split, std::vector<Op>& ops, TraversalStats& s, uint32_t max_bytes) {
  const Op op{node, split};
  const uint32_t bytes = op_wire_bytes(model_.pm, op);
  if (s.batch_bytes + bytes > max_bytes) return false;
  newly_s_.clear();
  newly_c_.clear();
  const uint32_t delta = triangle_delta(node);
  if (split) {
    cut_.split(node, &newly_s_, &newly_c_);
    triangles_ += delta, s.triangle_change += delta, ++s.splits;
  } else {
    cut_.collapse(node, &newly_s_, &newly_c_);
    triangles_ -= delta, s.triangle_change -= delta, ++s.collapses;
  }
  s.batch_bytes += bytes;
  ops.push_back(op);
  enqueue(newly_s_, false);
  enqueue(newly_c_, true);
  return true;
}

// Fig. 4.7: every legal front node evaluated into a queue ordered by need (F_c smallest first,
// F_s largest first); pop until the limit or the first node that needs nothing; the nodes an op
// brings onto the front are evaluated and queued too.
void Traversal::priority_pass(const View& v, bool collapse, const PassLimits& limits, std::vector<Op>& ops,
                              TraversalStats& s, uint32_t max_bytes) {
  std::deque<uint32_t>& front = collapse ? fc_ : fs_;
  const uint8_t bit = collapse ? kInC : kInS;
  const auto legal = [&](uint32_t n) { return collapse ? cut_.can_collapse(n) : cut_.can_split(n); };
  // Collapse: a min-queue of need; split: a max-queue (negated keys).
  using Entry = std::pair<float, uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  const auto consider = [&](uint32_t n) {
    const float x = need(n, v);
    ++s.evaluated;
    if (collapse ? x < 1 : x >= 1) queue.emplace(collapse ? x : -x, n);
  };
  std::erase_if(front, [&](uint32_t n) {
    if (legal(n)) return false;
    queued_[n] &= ~bit;
    return true;
  });
  for (uint32_t n : front) consider(n);
  uint32_t done = 0, added = 0;
  while (!queue.empty() && done < limits.ops) {
    const uint32_t n = queue.top().second;
    queue.pop();
    if (!legal(n)) continue;
    if (!collapse && added + triangle_delta(n) > limits.triangles) break;
    if (!apply(n, !collapse, ops, s, max_bytes)) break;
    ++done;
    added += triangle_delta(n);
    for (uint32_t m : collapse ? newly_c_ : newly_s_) consider(m);
  }
}

// Figs. 4.8/4.9: the front's FIFO, kept across frames. A node that needs nothing goes to the
// back; the pass ends at the limit, after a whole pass with no op, or (constant-time) after
// `limit` evaluations.
void Traversal::fifo_pass(const View& v, bool collapse, const PassLimits& limits, std::vector<Op>& ops,
                          TraversalStats& s, uint32_t max_bytes) {
  std::deque<uint32_t>& front = collapse ? fc_ : fs_;
  const uint8_t bit = collapse ? kInC : kInS;
  uint32_t done = 0, added = 0, evaluated = 0, since_op = 0;
  while (!front.empty() && done < limits.ops && evaluated < limits.evaluated) {
    const uint32_t n = front.front();
    front.pop_front();
    if (!(collapse ? cut_.can_collapse(n) : cut_.can_split(n))) {
      queued_[n] &= ~bit;
      continue;
    }
    const float x = need(n, v);
    ++evaluated, ++s.evaluated;
    const bool wanted = collapse ? x < 1 : x >= 1;
    const bool fits = collapse || added + triangle_delta(n) <= limits.triangles;
    if (wanted && fits) {
      queued_[n] &= ~bit;
      if (!apply(n, !collapse, ops, s, max_bytes)) {
        queued_[n] |= bit;
        front.push_front(n);
        return;
      }
      ++done;
      added += triangle_delta(n);
      since_op = 0;
      continue;
    }
    front.push_back(n);
    if (wanted || ++since_op >= front.size()) return;  // out of budget, or a whole pass and nothing to do
  }
}

TraversalStats Traversal::manage(const ViewParams& vp, std::vector<Op>& ops, uint32_t max_bytes) {
  const Vec3 dir = glm::normalize(vp.aim - vp.eye);
  const View v{vp.eye, dir, std::cos(vp.alpha), std::sin(vp.alpha), 2 * vp.tau * std::tan(vp.alpha)};
  TraversalStats s;
  const auto pass = [&](bool collapse, const PassLimits& limits) {
    if (kind_ == TraversalKind::kPriority) priority_pass(v, collapse, limits, ops, s, max_bytes);
    else fifo_pass(v, collapse, limits, ops, s, max_bytes);
  };
  // N bounds the ops a direction makes, or for constant-time the nodes it evaluates.
  const bool constant = kind_ == TraversalKind::kConstant;
  PassLimits limits;
  (constant ? limits.evaluated : limits.ops) = vp.n;
  const uint32_t before = triangles_;
  pass(true, limits);
  // BUDGET: add no more triangles than the collapses removed; a budget: no more than reach it.
  if (vp.budget > 0) limits.triangles = vp.budget > triangles_ ? vp.budget - triangles_ : 0;
  else if (vp.mode == BudgetMode::kBudget) limits.triangles = before - triangles_;
  pass(false, limits);
  return s;
}

uint32_t Traversal::front_size() const {
  uint32_t n = 0;
  for (uint32_t i : fs_) n += cut_.can_split(i);
  for (uint32_t i : fc_) n += cut_.can_collapse(i);
  return n;
}

uint64_t Traversal::byte_size() const {
  return cut_.byte_size() + queued_.size() + (fs_.size() + fc_.size()) * sizeof(uint32_t) +
         (newly_s_.capacity() + newly_c_.capacity()) * sizeof(uint32_t);
}

}  // namespace cellwalk::vdr
