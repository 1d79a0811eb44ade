// libFuzzer target for the R-tree section (src/index, docs/format.md "Section rtree"): any bytes
// must open and check as a tree, or give a cellwalk::Error; a tree that checks must answer a box
// search with in-range, distinct object ids; never a crash, a hang or an unbounded allocation.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <set>

#include "cellwalk/core/error.hpp"
#include "cellwalk/index/rtree.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cellwalk;
  try {
    const DiskRTree tree(std::vector<uint8_t>(data, data + size), "fuzz");
    tree.check();
    RTreeCacheOptions options;
    options.policy = RTreeCacheOptions::Policy::kNone;
    RTreeNodeCache cache(tree, options);
    std::vector<uint32_t> found;
    SearchCounters counters;
    box_search(cache, tree.bounds(), found, counters);
    std::set<uint32_t> distinct(found.begin(), found.end());
    if (distinct.size() != found.size()) std::abort();
    for (uint32_t id : found)
      if (id >= tree.object_count()) std::abort();
  } catch (const Error&) {
  }
  return 0;
}
