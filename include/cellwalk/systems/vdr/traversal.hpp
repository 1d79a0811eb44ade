// Zheng's server-side traversal of one client's cut (seed 004, §3.4 run-time view tests,
// §4.3 MANAGE-TRAVERSAL, §4.4 the priority, linear and constant-time traversals; digest
// §3.3–§3.6).
//
// Each node is judged by one number, its need v = error / threshold, where
//   error      = ap_err (thesis-exact: the raw quadric error) or sqrt(ap_err) (ErrorUnits::kLength)
//   threshold  = 2 τ tan(α) d,  d = (v_c − e)·n   (τ: a fraction of the viewport, α the view
//                cone's half-angle, n the view direction)
// and v = 0 for a node out of view ((γ − φ) > α, sin φ = rad / |v_c − e|) or back-facing
// (((v_c − e)/|v_c − e|)·a > sin θ). A node of F_s is split iff v ≥ 1; a node of F_c is
// collapsed iff v < 1. The priority traversal takes F_c by increasing v and F_s by decreasing v
// and stops at the first node that needs nothing; the linear one walks a FIFO per front that
// persists across frames; the constant-time one is the linear one with N counting the nodes it
// evaluates instead of the ops it makes.
//
// Thread-safety: none; one session owns a Traversal. The model is shared read-only.
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "cellwalk/systems/vdr/cut_state.hpp"
#include "cellwalk/systems/vdr/vdr_file.hpp"

namespace cellwalk::vdr {

enum class TraversalKind : uint8_t { kPriority = 0, kLinear = 1, kConstant = 2 };
std::string traversal_name(TraversalKind kind);  // "priority", "linear", "constant"
TraversalKind parse_traversal(const std::string& word);

// §4.3: FREE splits up to N; BUDGET splits only as many triangles as the collapses removed.
enum class BudgetMode : uint8_t { kFree = 0, kBudget = 1 };
// The thesis compares the raw quadric error with a length; kLength takes its square root.
enum class ErrorUnits : uint8_t { kThesis = 0, kLength = 1 };

// What a client sends each frame (digest §4 "Request").
struct ViewParams {
  Vec3 eye{0.0f}, aim{0.0f, 0.0f, -1.0f};  // aim: a point looked at
  float alpha = 0.6f;    // the view cone's half-angle, radians (the frustum diagonal's)
  float tau = 0.001f;    // screen-space tolerance, a fraction of the viewport
  BudgetMode mode = BudgetMode::kFree;
  uint32_t n = 500;      // ops per direction per frame (nodes evaluated, for constant-time)
  // B held by the server (beyond the thesis; docs/vdr.md "The budget"): when non-zero the splits
  // add no more triangles than leave the cut at B, and `mode` is not read. The cut the server
  // holds is the mesh the client will have once every batch sent is applied, so the client never
  // passes B, however many batches are in flight — without the alarm level's 2Nf of headroom.
  uint32_t budget = 0;
};

// One op of a batch, in the order the client must apply it.
struct Op {
  uint32_t node;
  bool split;
};

// The bytes an op takes in a batch (docs/vdr.md "Limits"): a vsplit carries v_c's position
// and normal; both carry v_p and the adjusted triangles (an ecol has no hierarchy to find them).
uint32_t op_wire_bytes(const ProgressiveMesh& pm, const Op& op);

struct TraversalStats {
  uint32_t collapses = 0, splits = 0;
  uint32_t evaluated = 0;       // nodes whose need was computed
  int64_t triangle_change = 0;  // triangles added minus removed
  uint32_t batch_bytes = 0;     // op_wire_bytes summed
};

class Traversal {
 public:
  // REQUIRES: `model` outlives the traversal.
  Traversal(const VdrModel& model, TraversalKind kind, ErrorUnits units = ErrorUnits::kThesis);

  // MANAGE-TRAVERSAL(vp, mode, N): TRAVERSE-COLLAPSE then TRAVERSE-SPLIT. Appends the ops to
  // `ops` (ecols first, then vsplits) and applies them to the cut; stops early rather than let
  // the batch pass `max_bytes`.
  TraversalStats manage(const ViewParams& vp, std::vector<Op>& ops, uint32_t max_bytes = 64 * 1024);

  // The need of node i under vp (0 when culled); exposed for tests and the reference run.
  float need(uint32_t i, const ViewParams& vp) const;

  const CutState& cut() const { return cut_; }
  uint32_t triangle_count() const { return triangles_; }
  // Legal nodes on each front now (stale entries not counted): Table 4.3's "front nodes".
  uint32_t front_size() const;
  // Bytes this session holds beyond the shared model: cut, flags and fronts.
  uint64_t byte_size() const;

 private:
  struct View;  // vp prepared once per frame
  // What one pass may do: ops, triangles added (BUDGET mode's splits) and nodes evaluated
  // (constant-time).
  struct PassLimits {
    uint32_t ops = 0xFFFFFFFFu, triangles = 0xFFFFFFFFu, evaluated = 0xFFFFFFFFu;
  };
  float need(uint32_t i, const View& v) const;
  void priority_pass(const View& v, bool collapse, const PassLimits& limits, std::vector<Op>& ops, TraversalStats& s,
                     uint32_t max_bytes);
  void fifo_pass(const View& v, bool collapse, const PassLimits& limits, std::vector<Op>& ops, TraversalStats& s,
                 uint32_t max_bytes);
  // Applies one op if the batch has room; false when it does not.
  bool apply(uint32_t node, bool split, std::vector<Op>& ops, TraversalStats& s, uint32_t max_bytes);
  void enqueue(const std::vector<uint32_t>& nodes, bool collapse_front);
  uint32_t triangle_delta(uint32_t node) const;

  const VdrModel& model_;
  TraversalKind kind_;
  ErrorUnits units_;
  CutState cut_;
  // The fronts with lazy invalidation (§4.2): a node is queued once (its flag bit set) and
  // dropped when a pass finds it no longer legal.
  std::deque<uint32_t> fs_, fc_;
  std::vector<uint8_t> queued_;  // bit 0: in fs_, bit 1: in fc_
  std::vector<uint32_t> newly_s_, newly_c_;
  uint32_t triangles_;
};

}  // namespace cellwalk::vdr
