// The disk HDoV-tree of VISUAL (HDoV thesis ch. 5; digest §2.2–2.3, §3.7–3.11, §4): the R-tree
// of REVIEW whose entries carry, per view cell, VD = (DoV, NVO) and whose nodes carry internal
// LODs (aggregates of the subtree simplified bottom-up, §5.6). The view-invariant node parts
// (boxes, pointers, LOD pointers) are one page per node; the view-variant VDs are V-pages, one
// per (node, cell), stored in three schemes (§5.4): horizontal, vertical and indexed-vertical,
// with V-page index segments, DFS order and the cell flip. A side file "<world>.hdov" (a world
// file container: page checksums, sections) holds all of it; layout in docs/format.md,
// "HDoV-tree file". Choices where the thesis is silent: docs/visual.md.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/store/buffer_manager.hpp"
#include "cellwalk/lod/lod.hpp"
#include "cellwalk/index/rtree.hpp"
#include "cellwalk/visibility/view_cell.hpp"
#include "cellwalk/visibility/visibility.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

// One V-entry: the VD of a node's entry in one cell (8 bytes on disk: f32 DoV, u32 NVO).
struct VEntry {
  float dov = 0.0f;
  uint32_t nvo = 0;
  bool operator==(const VEntry&) const = default;
};

enum class VPageScheme : uint32_t { kHorizontal = 0, kVertical = 1, kIndexedVertical = 2 };
const char* vpage_scheme_name(VPageScheme scheme);  // "horizontal", "vertical", "indexed-vertical"
// Accepts the names above and "h", "v", "iv". Throws Error on anything else.
VPageScheme parse_vpage_scheme(const std::string& name);

struct HdovBuildParams {
  uint32_t page_size = kDefaultPageSize;  // one node per page
  uint32_t max_entries = 16;              // M; REQUIRES the node page to hold M entries + its LODs
  RTreeMethod method = RTreeMethod::kLinearInsert;
  AggregateLodParams lods;                // internal LODs per node
};

// Where an internal LOD lies in the file's geometry section.
struct HdovLodRef {
  uint64_t offset = 0;
  uint32_t bytes = 0;
  uint32_t triangles = 0;
};

// The view-invariant part of a node: what its page holds.
struct HdovNode {
  uint32_t height = 0;          // 0 for a leaf
  uint32_t objects = 0;         // objects below (m of eq. 5.3)
  uint64_t leaf_triangles = 0;  // Σ level-0 triangles of the objects below
  std::vector<RTreeEntry> entries;  // child node ids (DFS numbering) or, in a leaf, object ids
  std::vector<HdovLodRef> lods;     // internal LODs, finest first (may be empty)
  bool leaf() const { return height == 0; }
};

// What the build and the file share.
struct HdovTreeBuild {
  HdovBuildParams params;
  uint64_t object_count = 0;
  uint64_t world_triangles = 0;        // identifies the world the tree belongs to
  std::vector<uint8_t> cells;          // serialize_partition() of the view cells
  uint32_t cell_count = 0;
  std::vector<HdovNode> nodes;         // depth-first preorder: root 0, children after parents
  std::vector<uint8_t> geometry;       // encoded internal LODs
  // vd[cell][node]: one V-entry per entry of the node, or empty when the node is invisible
  // from the cell (no entry has DoV > 0).
  std::vector<std::vector<std::vector<VEntry>>> vd;
  uint32_t vpage_size() const { return 8 * params.max_entries; }
  uint64_t visible_nodes() const;      // Σ over cells of N_vnode(cell)
};

// The DoVs of one cell's visible objects (nullopt: a solid cell, nothing visible). Not called for
// skipped cells.
using CellDovSource = std::function<std::optional<VisibleSet>(CellId)>;

// Builds the tree over `world`'s objects: the R-tree, renumbered depth first; internal LODs
// bottom-up (a leaf node aggregates its objects' coarsest levels, an internal node its
// children's coarsest internal LODs); per cell, leaf entries get the object's DoV (NVO 1 when
// DoV > 0) and an internal entry the sums over its child node's entries (so invariant 2 of §4
// holds exactly). Called with (steps done, total).
HdovTreeBuild build_hdov_tree(const World& world, const ViewCellPartition& cells, const CellDovSource& dov,
                              const HdovBuildParams& params,
                              const std::function<void(uint64_t, uint64_t)>& progress = {});

// The default side file of a world: "<world>.hdov".
std::string default_hdov_path(const std::string& world_path);
// Writes every section (all three schemes and the naive lists) atomically to `path`.
void write_hdov_tree(const HdovTreeBuild& tree, const std::string& path);

// Storage of one scheme's V-data (V-pages + V-page index), measured and by formula.
struct SchemeStorage {
  uint64_t vpage_bytes = 0;      // V-pages
  uint64_t index_bytes = 0;      // V-page index segments
  uint64_t directory_bytes = 0;  // indexed-vertical's cell → segment index (not in eq. 5.9)
  uint64_t total() const { return vpage_bytes + index_bytes + directory_bytes; }
};
// Eqs. 5.7–5.9 with size_vpage = 8 M, size_pointer = size_integer = 4 and N_vnode·c taken as
// Σ_cells N_vnode(cell); the directory term (8 bytes a cell) is added for indexed-vertical.
SchemeStorage formula_storage(VPageScheme scheme, uint64_t nodes, uint64_t cells, uint64_t visible_nodes,
                              uint64_t vpage_size);

// Bounds-checked decoders (a damaged page gives one Error naming `where`).
// REQUIRES nothing of the bytes; checks count and LOD refs against the page, finite boxes.
HdovNode decode_hdov_node(std::span<const uint8_t> page, const std::string& where);
// Checks DoV finite and >= 0 and that entries past `entries` are zero.
std::vector<VEntry> decode_vpage(std::span<const uint8_t> bytes, uint32_t entries, const std::string& where);

// Page accesses of searches and flips, for the thesis's light-weight I/O.
struct HdovCounters {
  uint64_t node_visits = 0, node_reads = 0;  // node pages looked at / read (cache misses)
  uint64_t vpage_reads = 0;                   // V-pages read (one I/O each)
  uint64_t vpage_seeks = 0;                   // of those, not adjacent to the previous one read
  uint64_t index_reads = 0;                   // pages of V-page index segments read by flips
  uint64_t index_bytes = 0;                   // bytes of those segments (the flip's cost, §5.4)
  uint64_t list_reads = 0;                    // pages of the naive method's lists read
  uint64_t light_ios() const { return node_reads + vpage_reads + index_reads + list_reads; }
};

// An opened HDoV-tree file. Thread-safety: const methods may be called concurrently.
class HdovTree {
 public:
  // Throws Error naming the file if it is damaged or belongs to another world.
  HdovTree(const World& world, const std::string& path);
  ~HdovTree();

  const World& world() const { return world_; }
  const ViewCellPartition& cells() const { return *cells_; }
  uint32_t page_size() const { return page_size_; }
  uint32_t max_entries() const { return max_entries_; }
  uint32_t vpage_size() const { return 8 * max_entries_; }
  uint32_t node_count() const { return node_count_; }
  uint32_t cell_count() const { return cell_count_; }
  uint32_t height() const { return height_; }  // levels
  SchemeStorage storage(VPageScheme scheme) const;  // the sections' sizes
  uint64_t naive_bytes() const;                      // the naive lists and their directory

  HdovNode read_node(uint32_t node) const;
  // The V-page at byte `offset` of a scheme's V-page section, for a node of `entries` entries.
  std::vector<VEntry> read_vpage(VPageScheme scheme, uint64_t offset, uint32_t entries) const;
  // The bytes [offset, offset + length) of a section (index segments, lists).
  std::vector<uint8_t> read_bytes(const char* section, uint64_t offset, uint64_t length) const;
  Mesh read_lod(const HdovLodRef& lod) const;
  // The indexed-vertical cell directory: (first pair, pair count) per cell; read when opened.
  const std::vector<std::pair<uint32_t, uint32_t>>& iv_directory() const { return iv_directory_; }
  const std::vector<uint64_t>& naive_directory() const { return naive_directory_; }
  uint64_t resident_bytes() const;

 private:
  const World& world_;
  std::unique_ptr<WorldFile> file_;
  std::unique_ptr<ViewCellPartition> cells_;
  uint32_t page_size_ = 0, max_entries_ = 0, node_count_ = 0, cell_count_ = 0, height_ = 0;
  std::vector<std::pair<uint32_t, uint32_t>> iv_directory_;
  std::vector<uint64_t> naive_directory_;  // cell_count + 1 offsets into the lists
};

// ---- Searching (§5.3, Fig. 5.4) ---------------------------------------------------------------

// What a search draws: an object at one of its levels, or a node's internal LOD.
struct HdovPick {
  bool internal = false;
  uint32_t id = 0;     // object id, or node id of an internal LOD
  uint32_t level = 0;
  uint32_t triangles = 0;
  auto operator<=>(const HdovPick&) const = default;
};

struct HdovSearchParams {
  double eta = 0.0;      // η: a subtree of DoV <= η may stop at its internal LOD
  double max_dov = 0.5;  // MAXDOV of eq. 5.6
};

// The level of a leaf object by eq. 5.6: target triangles k·T_finest + (1−k)·T_coarsest,
// k = min(DoV / max_dov, 1), snapped to the nearest stored level (ties to the finer).
uint32_t leaf_level(const World& world, ObjectId object, double dov, double max_dov);

// How node pages are cached (§5.7): none, LRU, DoV or DoV-Time (κ = 0.001) through the store's
// BufferManager, `pages` node pages at most (each charged page_size bytes). DoV-Time's T counts
// searches (each search() is one query, digest §3.11); kDovTimeAccess counts page requests
// instead, kept to show what the time unit does (docs/visual.md).
struct HdovCacheOptions {
  enum class Policy { kNone, kLru, kDov, kDovTime, kDovTimeAccess };
  Policy policy = Policy::kDovTime;
  uint64_t pages = 64;
  double kappa = 0.001;
};
HdovCacheOptions::Policy parse_hdov_cache_policy(const std::string& name);  // none|lru|dov|dt|dt-access
const char* hdov_cache_policy_name(HdovCacheOptions::Policy policy);

// The search of one scheme over one tree: flip() loads the cell's V-page index segment, search()
// runs the threshold traversal. Thread-safety: none.
class HdovSearcher {
 public:
  // REQUIRES: `tree` outlives the searcher.
  HdovSearcher(const HdovTree& tree, VPageScheme scheme, const HdovCacheOptions& cache);
  ~HdovSearcher();

  // The cell flip: the current cell becomes `cell` (reads its segment; horizontal: nothing).
  void flip(CellId cell, HdovCounters& counters);
  std::optional<CellId> cell() const { return cell_; }
  // Fig. 5.4 with `continue` on DoV = 0: leaves at eq. 5.6's level; an internal entry with
  // DoV <= η whose child's finest LOD costs fewer triangles than its visible objects would
  // (eq. 5.4, see docs/visual.md) becomes the child's LOD at eq. 5.5's level. Appends to `out`
  // in traversal order. REQUIRES: flip() was called.
  void search(const HdovSearchParams& params, std::vector<HdovPick>& out, HdovCounters& counters);

  // Bytes held: the segment and the node cache (at most its limit).
  uint64_t resident_bytes() const;
  uint64_t peak_bytes() const;
  BufferCounters cache_counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::optional<CellId> cell_;
};

// The naive (cell, list-of-objects) method: the cell's list of visible objects and DoVs, read
// sequentially, every object at eq. 5.6's level. Equals search() with η = 0 as a set.
void naive_search(const HdovTree& tree, CellId cell, double max_dov, std::vector<HdovPick>& out,
                  HdovCounters& counters);

}  // namespace cellwalk
