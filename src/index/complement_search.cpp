// HDoV thesis §4.2.2 (digest §3.3): the R-tree box search and CSearch, the complement search
// that returns only objects no earlier cell returned, with COverlap ("not completely inside").
#include <algorithm>

#include "cellwalk/index/rtree.hpp"

namespace cellwalk {
namespace {

// Fig. 4.5 with an empty history is the plain box search (Guttman's Search).
void csearch(RTreeNodeCache& cache, uint32_t index, uint32_t depth, const Aabb& box, const Aabb& cell,
             std::span<const Aabb> history, std::vector<uint32_t>& out, SearchCounters& counters) {
  const std::shared_ptr<const RTreeNode> node = cache.node(index, depth, box, counters);
  for (const RTreeEntry& e : node->entries) {
    if (!e.box.overlaps(cell)) continue;  // lines 3 and 9
    if (node->leaf()) {
      // Line 10: Overlaps none of C1..Ci.
      if (std::none_of(history.begin(), history.end(), [&](const Aabb& h) { return e.box.overlaps(h); }))
        out.push_back(e.ref);
    } else if (std::all_of(history.begin(), history.end(), [&](const Aabb& h) { return coverlaps(e.box, h); })) {
      // Line 4: COverlaps all of C1..Ci, i.e. not completely inside any of them.
      csearch(cache, e.ref, depth + 1, e.box, cell, history, out, counters);
    }
  }
}

}  // namespace

bool coverlaps(const Aabb& box, const Aabb& cell) { return !cell.contains(box); }

void box_search(RTreeNodeCache& cache, const Aabb& cell, std::vector<uint32_t>& out, SearchCounters& counters) {
  complement_search(cache, cell, {}, out, counters);
}

void complement_search(RTreeNodeCache& cache, const Aabb& cell, std::span<const Aabb> history,
                       std::vector<uint32_t>& out, SearchCounters& counters) {
  cache.begin_query(cell);
  csearch(cache, 0, 0, cache.tree().bounds(), cell, history, out, counters);
}

}  // namespace cellwalk
