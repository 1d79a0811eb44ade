// One client's cut of the vsplit DAG on the server (seed 004, §4.2 "numbering mechanism",
// Fig. 4.3; digest §3.4): a status bit and a counter per node over the shared, read-only DAG.
//   collapsed node: counter = its collapsed parents   -> splittable   iff 0 (the front F_s)
//   split node:     counter = its split children      -> collapsible  iff 0 (the front F_c)
// Initially every node is collapsed with counter = its in-degree, so F_s = the roots.
// SPLIT-MAINTENANCE(t) zeroes t's counter (it has no split child), decrements its children's
// (those reaching 0 join F_s) and increments its parents' (they leave F_c: lazily, a front's
// reader checks can_split / can_collapse when it pops). COLLAPSE-MAINTENANCE is its mirror.
//
// Thread-safety: none; one session owns it. 3 bytes per node.
#pragma once

#include <cstdint>
#include <vector>

#include "cellwalk/systems/vdr/vsplit_dag.hpp"

namespace cellwalk::vdr {

class CutState {
 public:
  // REQUIRES: `dag` outlives this state. Throws Error when a node has 65,535 or more edges on
  // one side (the counters are 16-bit).
  explicit CutState(const VsplitDag& dag);

  bool is_split(uint32_t i) const { return split_[i] != 0; }
  uint16_t counter(uint32_t i) const { return counter_[i]; }
  bool can_split(uint32_t i) const { return !split_[i] && counter_[i] == 0; }
  bool can_collapse(uint32_t i) const { return split_[i] && counter_[i] == 0; }

  // REQUIRES can_split(t) / can_collapse(t). Appends to `splittable` the nodes that became
  // splittable (after split: t's children reaching 0; after collapse: t itself) and to
  // `collapsible` those that became collapsible (after split: t; after collapse: t's parents
  // reaching 0). Either may be null.
  void split(uint32_t t, std::vector<uint32_t>* splittable = nullptr, std::vector<uint32_t>* collapsible = nullptr);
  void collapse(uint32_t t, std::vector<uint32_t>* splittable = nullptr, std::vector<uint32_t>* collapsible = nullptr);

  uint32_t split_count() const { return split_nodes_; }
  uint64_t byte_size() const { return split_.size() + counter_.size() * sizeof(uint16_t); }

 private:
  const VsplitDag& dag_;
  std::vector<uint8_t> split_;
  std::vector<uint16_t> counter_;
  uint32_t split_nodes_ = 0;
};

}  // namespace cellwalk::vdr
