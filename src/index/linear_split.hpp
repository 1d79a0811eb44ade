// Ang & Tan's linear node split for R-trees (C. H. Ang and T. C. Tan, "New linear node
// splitting algorithm for R-trees", SSD 1997), as the HDoV thesis uses it (§2.2.1, §4.1;
// digest §3.2).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "cellwalk/index/rtree.hpp"

namespace cellwalk {

// Splits an overflowing node's entries into two groups. Each entry goes to the list of the
// border of the node's box it is nearer to, per axis (2d lists); the axis whose two lists have
// the closest sizes wins, ties broken by the smaller overlap of the two groups' boxes, then by
// the smaller total volume. If the winner leaves a group below `min_entries`, the entries of the
// other group nearest that border move over (ours: the paper leaves the underflow open).
// REQUIRES: entries.size() >= 2 * min_entries, min_entries >= 1.
std::pair<std::vector<RTreeEntry>, std::vector<RTreeEntry>> linear_split(std::vector<RTreeEntry> entries,
                                                                         uint32_t min_entries);

}  // namespace cellwalk
