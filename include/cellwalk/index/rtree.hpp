// The paged, disk-resident 3-D R-tree of REVIEW (HDoV thesis §4.2.1, digest §3.2): Guttman's
// R-tree over the objects' bounding boxes, built by insertion with Ang & Tan's linear node
// split (or, as an option, packed by Sort-Tile-Recursive), stored one node per page in the
// world file's "rtree" section (docs/format.md, "Section rtree"), and read back one page per
// node so every node access that misses the cache is exactly one page read.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/store/buffer_manager.hpp"
#include "cellwalk/core/geometry.hpp"
#include "cellwalk/store/replacement_policy.hpp"

namespace cellwalk {

class World;
class WorldWriter;

inline constexpr const char* kRTreeSection = "rtree";

// One entry of a node: a child node (inner nodes) or an object (leaves) and its box.
struct RTreeEntry {
  Aabb box;
  uint32_t ref = 0;  // child node index, or object id in a leaf
};

struct RTreeNode {
  uint32_t height = 0;  // 0 for a leaf; a parent is one higher than its children
  std::vector<RTreeEntry> entries;
  bool leaf() const { return height == 0; }
  Aabb bounds() const;
};

// Entries of one node page: (page_size - 8) / 28 (145 at 4 KiB).
uint32_t rtree_page_capacity(uint32_t page_size);

enum class RTreeMethod : uint32_t {
  kLinearInsert = 0,  // one insertion per object, Ang & Tan's linear split on overflow (default)
  kStr = 1,           // Sort-Tile-Recursive bulk load (full nodes; an option, not the thesis's)
};

struct RTreeParams {
  uint32_t max_entries = 0;  // M; 0 = as many as fit a page
  uint32_t min_entries = 0;  // m, 2 <= m <= M/2; 0 = 40 % of M
  RTreeMethod method = RTreeMethod::kLinearInsert;
};

// A built tree in memory, nodes numbered breadth first: node 0 is the root, each level follows
// the one above it.
struct RTreeBuild {
  uint32_t page_size = 0;
  uint32_t max_entries = 0, min_entries = 0;
  RTreeMethod method = RTreeMethod::kLinearInsert;
  uint64_t object_count = 0;
  Aabb bounds;  // of every object
  std::vector<RTreeNode> nodes;
  uint32_t height() const { return nodes.empty() ? 0 : nodes[0].height + 1; }
};

// Builds the tree of `boxes` (object id = index). Throws Error if the parameters are invalid
// (M above the page capacity or below 4, m outside [2, M/2]). An empty input gives one empty
// leaf as the root.
RTreeBuild build_rtree(std::span<const Aabb> boxes, const RTreeParams& params, uint32_t page_size);

// The section's bytes: a header page, then one page per node in index order.
std::vector<uint8_t> encode_rtree_section(const RTreeBuild& tree);
// Writes the same bytes as a new "rtree" section of `writer`, a page at a time.
void write_rtree_section(const RTreeBuild& tree, WorldWriter& writer);
// Rewrites the world file `path` with a (new or replacing) "rtree" section built from its
// objects' boxes; every other section is copied unchanged. Atomic like every world write.
RTreeBuild add_rtree_to_world(const std::string& path, const RTreeParams& params);

// Decodes one node page. Bounds-checked: a damaged page gives one Error naming `where`.
// REQUIRES nothing of the bytes; checks count <= capacity, the height, finite boxes.
RTreeNode decode_rtree_node(std::span<const uint8_t> page, const std::string& where);

// Reads a stored R-tree: the header once, then single node pages on request.
// Thread-safety: read_node may be called concurrently.
class DiskRTree {
 public:
  // From a world's "rtree" section; throws Error naming the world (and `cellwalk build`) if it
  // has none or its header is damaged.
  explicit DiskRTree(const World& world);
  // From section bytes in memory (tests, fuzzing).
  explicit DiskRTree(std::vector<uint8_t> section, std::string name = "rtree");

  uint32_t page_size() const { return page_size_; }
  uint32_t max_entries() const { return max_entries_; }
  uint32_t min_entries() const { return min_entries_; }
  RTreeMethod method() const { return method_; }
  uint32_t height() const { return height_; }  // levels; 1 = the root is a leaf
  uint64_t node_count() const { return node_count_; }
  uint64_t object_count() const { return object_count_; }
  const Aabb& bounds() const { return bounds_; }

  // Reads node `index` (one page) and checks it holds `height` and refs in range.
  RTreeNode read_node(uint32_t index, uint32_t height) const;
  // Walks the whole tree (every page once) and checks that every entry's box is its child's
  // bounds, every object appears exactly once and leaves share one depth. Returns the nodes
  // visited; throws Error naming the first broken node.
  uint64_t check() const;

 private:
  void parse_header(std::span<const uint8_t> bytes);

  std::string name_;
  std::function<std::vector<uint8_t>(uint64_t offset, uint64_t length)> read_;
  uint32_t page_size_ = 0, max_entries_ = 0, min_entries_ = 0, height_ = 0;
  RTreeMethod method_ = RTreeMethod::kLinearInsert;
  uint64_t node_count_ = 0, object_count_ = 0;
  Aabb bounds_;
};

// Page accesses of one search, for the thesis's "disk I/Os per query".
struct SearchCounters {
  uint64_t node_visits = 0;  // nodes the search looked at
  uint64_t node_reads = 0;   // of those, read from the file (cache misses): one page each
};

// How the R-tree's nodes are cached (HDoV thesis §4.2.4, digest §3.4): LRU or distance-priority
// LRU through the store's BufferManager under a byte limit of their own, the root pinned; or no
// cache at all (configuration NC, and BOX): every node visit is a page read.
struct RTreeCacheOptions {
  enum class Policy { kNone, kLru, kDistancePriorityLru };
  Policy policy = Policy::kDistancePriorityLru;
  uint64_t bytes = 1 << 20;  // the index cache's size (the thesis's default 1 MB)
  DistancePriorityWeights weights;  // α = β = γ = 1/3
};

// The allocator's cost per heap block (glibc: an 8-byte header, 16-byte granularity), used by the
// per-entry bookkeeping estimates of the index cache and REVIEW's object buffer.
inline constexpr uint64_t kHeapBlockBytes = 16;

// What one decoded node of `tree` costs resident, at most: its page or its decoded entries
// (M of them), whichever is larger, plus its heap blocks and the node cache's bookkeeping for it
// (the BufferManager's and the policy's entries, estimated from their node types). The index
// cache charges each node this way (with its actual entry count); a search holds one node per
// level beside the cache.
uint64_t rtree_node_resident_bound(const DiskRTree& tree);

// Node access for the searches. Thread-safety: node() may be called concurrently.
class RTreeNodeCache {
 public:
  // Loads and pins the root when caching. Throws Error if `options.bytes` cannot hold the root.
  // REQUIRES: `tree` outlives the cache.
  RTreeNodeCache(const DiskRTree& tree, const RTreeCacheOptions& options);
  ~RTreeNodeCache();

  const DiskRTree& tree() const { return tree_; }
  // Node `index` at `depth` (root 0) whose parent entry's box is `box`; counts the visit and,
  // on a miss, the page read.
  std::shared_ptr<const RTreeNode> node(uint32_t index, uint32_t depth, const Aabb& box,
                                        SearchCounters& counters);
  // A new query with cell `cell` begins: DPLRU ages its entries and measures distances to it.
  void begin_query(const Aabb& cell);

  // Bytes the cache holds (its own budget's use) and its limit (0 without a cache).
  uint64_t resident_bytes() const { return budget_.used(); }
  uint64_t peak_bytes() const { return budget_.peak(); }
  uint64_t limit_bytes() const;
  BufferCounters counters() const;

 private:
  const DiskRTree& tree_;
  RTreeCacheOptions options_;
  MemoryBudget budget_;
  std::unique_ptr<BufferManager> buffer_;  // null without a cache
};

// The thesis's COverlap(BB, A) (§4.2.2): BB meets the complement of A, i.e. BB is not
// completely contained in A (for boxes: some vertex of BB lies outside A).
bool coverlaps(const Aabb& box, const Aabb& cell);

// Plain R-tree box search: every object whose box overlaps `cell` (closed boxes), appended to
// `out` in tree order.
void box_search(RTreeNodeCache& cache, const Aabb& cell, std::vector<uint32_t>& out,
                SearchCounters& counters);

// CSearch(T, C, H) (thesis Fig. 4.5, digest §3.3): every object whose box overlaps `cell` and
// overlaps none of the `history` cells, appended to `out`. An inner entry is descended only if
// it overlaps `cell` and is not completely inside any history cell (the pseudo-code's reading;
// its objects would all overlap that cell). Never visits a node box_search would not visit.
void complement_search(RTreeNodeCache& cache, const Aabb& cell, std::span<const Aabb> history,
                       std::vector<uint32_t>& out, SearchCounters& counters);

}  // namespace cellwalk
