// Zheng's vertex-split DAG (seed 004, §3.3, Figs. 3.8–3.10; §3.4 visibility attributes; digest
// §3.2–§3.3): node i is vsplit i of a ProgressiveMesh; an edge p -> t says p must be split
// before t (and, reversed, that t must be collapsed before p: one DAG serves both directions).
// Three builders differ only in which potential parents become edges:
//   full       every potential parent (about 60 % of the edges are redundant);
//   non        the transitive reduction (Fig. 3.9: drop every potential parent that is an
//              ancestor of a kept one; O(n²) in the worst case);
//   mini       Fig. 3.10: drop a potential parent only if it is a potential parent of a kept
//              one (O(1) each: linear time, ~83 % of the redundant edges removed).
// All three have the same ancestors for every node.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/systems/vdr/progressive_mesh.hpp"

namespace cellwalk::vdr {

enum class DagKind : uint8_t { kFull = 0, kNonRedundant = 1, kMiniRedundant = 2 };
// "full", "non", "mini"; parse_dag_kind throws Error naming the accepted words.
std::string dag_kind_name(DagKind kind);
DagKind parse_dag_kind(const std::string& word);

// Per node, the §3.4 attributes the server's view tests read.
struct NodeAttributes {
  std::vector<float> rad;       // a sphere about v_c holding what the node and its descendants change
  std::vector<float> cone_sin;  // sin θ of the normal cone about n(v_c); 1 = never back-facing
  std::vector<float> ap_err;    // the largest collapse error QE of the node and its descendants
};

struct VsplitDag {
  DagKind kind = DagKind::kMiniRedundant;
  // CSR, both directions: parents of i are in_edges[in_offsets[i] .. in_offsets[i+1]), children
  // out_edges[...]; each list is sorted by increasing id. Every parent's id is below its child's.
  std::vector<uint32_t> in_offsets{0}, in_edges, out_offsets{0}, out_edges;
  NodeAttributes attributes;

  uint32_t node_count() const { return static_cast<uint32_t>(in_offsets.size() - 1); }
  uint64_t edge_count() const { return in_edges.size(); }
  std::span<const uint32_t> parents(uint32_t i) const {
    return {in_edges.data() + in_offsets[i], in_edges.data() + in_offsets[i + 1]};
  }
  std::span<const uint32_t> children(uint32_t i) const {
    return {out_edges.data() + out_offsets[i], out_edges.data() + out_offsets[i + 1]};
  }
  // Bytes the DAG and its attributes occupy in memory (Table 3.3's "memory").
  uint64_t byte_size() const;
};

// Fills out_offsets and out_edges from in_offsets and in_edges.
void derive_children(VsplitDag& dag);

using DagProgress = std::function<void(uint64_t, uint64_t)>;  // (nodes done, nodes)

// Builds the DAG of `pm` of the given kind and computes its attributes (compute_attributes).
VsplitDag build_vsplit_dag(const ProgressiveMesh& pm, DagKind kind, const DagProgress& progress = {});

// §3.4, bottom-up (by decreasing id, children first):
//   rad     = max(|v_c − v_p|, |v_c − v_l|, |v_c − v_r|), then max(rad, |v_c − v_c(d)| + rad(d))
//   θ       = min(π/2, max angle between n(v_c) and n(f_l), n(f_r)), then
//             max(θ, min(π/2, angle(n(v_c), n(v_c(d))) + θ(d))); cone_sin = sin θ
//   ap_err  = QE, then max over the children's ap_err.
// f_l and f_r's normals are those of the triangles the split makes.
NodeAttributes compute_attributes(const ProgressiveMesh& pm, const VsplitDag& dag);

}  // namespace cellwalk::vdr
