// Seed 004 (Zheng), §4.2 and Fig. 4.3: SPLIT- and COLLAPSE-MAINTENANCE on one client's cut.
#include "cellwalk/systems/vdr/cut_state.hpp"

#include <algorithm>
#include <cassert>
#include <string>

#include "cellwalk/core/error.hpp"

namespace cellwalk::vdr {

CutState::CutState(const VsplitDag& dag)
    : dag_(dag), split_(dag.node_count(), 0), counter_(dag.node_count(), 0) {
  for (uint32_t i = 0; i < dag.node_count(); ++i) {
    const size_t most = std::max(dag.parents(i).size(), dag.children(i).size());
    if (most >= 0xFFFF)
      fail("vsplit DAG node " + std::to_string(i), "has " + std::to_string(most) + " edges on one side; at most 65,534 fit a counter");
    counter_[i] = static_cast<uint16_t>(dag.parents(i).size());
  }
}

void CutState::split(uint32_t t, std::vector<uint32_t>* splittable, std::vector<uint32_t>* collapsible) {
  assert(can_split(t));
  split_[t] = 1;
  ++split_nodes_;
  counter_[t] = 0;  // a node just split has no split child
  if (collapsible) collapsible->push_back(t);
  for (uint32_t d : dag_.children(t))
    if (--counter_[d] == 0 && splittable) splittable->push_back(d);
  for (uint32_t p : dag_.parents(t)) ++counter_[p];
}

void CutState::collapse(uint32_t t, std::vector<uint32_t>* splittable, std::vector<uint32_t>* collapsible) {
  assert(can_collapse(t));
  split_[t] = 0;
  --split_nodes_;
  counter_[t] = 0;  // a node just collapsed has every parent split
  if (splittable) splittable->push_back(t);
  for (uint32_t p : dag_.parents(t))
    if (--counter_[p] == 0 && collapsible) collapsible->push_back(p);
  for (uint32_t d : dag_.children(t)) ++counter_[d];
}

}  // namespace cellwalk::vdr
