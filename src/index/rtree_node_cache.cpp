// The index buffer of REVIEW (HDoV thesis §3.2.1 "Buffer for Data Structure", §4.2.4; digest
// §3.4): R-tree node pages in the store's BufferManager under a byte limit of their own, with
// LRU or distance-priority LRU (α = β = γ = 1/3) and the root pinned; or no cache (NC, BOX).
#include <algorithm>

#include "cellwalk/core/error.hpp"
#include "cellwalk/index/rtree.hpp"

namespace cellwalk {
namespace {

BlockBox block_box(const Aabb& box) {
  BlockBox b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = box.min[a];
    b.hi[a] = box.max[a];
  }
  return b;
}

// Per cached node, beside its entries (an estimate from the node types): the shared_ptr control
// block and the allocator's headers on the node's block and its entry array; the BufferManager's
// map node (key, handle, size, pins, a link, two bucket slots); the policy's map node (key,
// EntryMeta, scores and clocks, a link, two bucket slots) and its ordered-set or list node
// (score, key, three links and a colour).
constexpr uint64_t kNodeBookkeepingBytes =
    2 * sizeof(long) + sizeof(void*) + 2 * kHeapBlockBytes +
    sizeof(CacheKey) + sizeof(CacheHandle) + 2 * sizeof(uint64_t) + 3 * sizeof(void*) + kHeapBlockBytes +
    sizeof(CacheKey) + sizeof(EntryMeta) + 4 * sizeof(uint64_t) + 3 * sizeof(void*) + kHeapBlockBytes +
    sizeof(double) + sizeof(CacheKey) + 4 * sizeof(void*) + kHeapBlockBytes;

// A resident node costs its page or its decoded entries, whichever is larger, and bookkeeping.
// The page itself is not kept: read_node decodes it and frees it.
uint64_t node_bytes(uint64_t entries, uint32_t page_size) {
  return std::max<uint64_t>(page_size, sizeof(RTreeNode) + entries * sizeof(RTreeEntry)) + kNodeBookkeepingBytes;
}

}  // namespace

uint64_t rtree_node_resident_bound(const DiskRTree& tree) { return node_bytes(tree.max_entries(), tree.page_size()); }

RTreeNodeCache::RTreeNodeCache(const DiskRTree& tree, const RTreeCacheOptions& options)
    : tree_(tree), options_(options), budget_(options.policy == RTreeCacheOptions::Policy::kNone ? 0 : options.bytes) {
  if (options.policy == RTreeCacheOptions::Policy::kNone) return;
  if (options.bytes < rtree_node_resident_bound(tree))
    fail("index cache", std::to_string(options.bytes) + " bytes cannot hold the R-tree's root page; give at least " +
                            std::to_string(rtree_node_resident_bound(tree)));
  buffer_ = std::make_unique<BufferManager>(budget_, options.policy == RTreeCacheOptions::Policy::kLru
                                                         ? make_lru_policy()
                                                         : make_distance_priority_lru_policy(options.weights));
  SearchCounters ignored;
  node(0, 0, tree.bounds(), ignored);
  if (!buffer_->contains(0)) fail("index cache", "the R-tree's root does not fit the index cache");
  buffer_->pin(0);
}

RTreeNodeCache::~RTreeNodeCache() {
  if (buffer_ && buffer_->contains(0)) buffer_->unpin(0);
}

std::shared_ptr<const RTreeNode> RTreeNodeCache::node(uint32_t index, uint32_t depth, const Aabb& box,
                                                      SearchCounters& counters) {
  ++counters.node_visits;
  const uint32_t height = tree_.height() - 1 - depth;
  auto load = [&]() -> LoadedItem {
    ++counters.node_reads;
    auto node = std::make_shared<const RTreeNode>(tree_.read_node(index, height));
    return {node, node_bytes(node->entries.capacity(), tree_.page_size())};
  };
  if (!buffer_) return std::static_pointer_cast<const RTreeNode>(load().value);
  EntryMeta meta;
  meta.level = depth;
  meta.box = block_box(box);
  return BufferManager::get_as<RTreeNode>(buffer_->get(index, meta, load));
}

void RTreeNodeCache::begin_query(const Aabb& cell) {
  if (buffer_) buffer_->begin_query(QueryContext{block_box(cell), 0});
}

uint64_t RTreeNodeCache::limit_bytes() const { return buffer_ ? options_.bytes : 0; }

BufferCounters RTreeNodeCache::counters() const { return buffer_ ? buffer_->counters() : BufferCounters{}; }

}  // namespace cellwalk
