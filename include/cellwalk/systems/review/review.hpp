// REVIEW, the spatial walkthrough system of the HDoV thesis, chapter 4 (digest §3.1–§3.6, §5.4):
// a frustum cell and a larger disk cell (SF × its size); when the frustum cell leaves the disk
// cell, a new disk cell is queried from the world's paged R-tree with CSearch, which returns only
// objects no cell in the history returned; R-tree pages are cached with distance-priority LRU;
// the next disk cell is prefetched at F' = F + k·v; the object buffer is culled against the view
// frustum with the exact convex-cell vs box test before drawing. docs/review.md has the design.
//
// Strategy names (make_strategy): "review" (Optimal: CSearch + index cache + prefetch),
// "review-nc" (no index cache), "review-np" (no prefetch), "review-box" (plain box queries, no
// cache, no prefetch, the buffer replaced by each query's result), each optionally followed by
// ":key=value,..." with keys
//   k=0.8            prefetch factor k (F' = far-plane centre + k·velocity, velocity in m/s of
//                    path time: FrameStats::time on entry to select())
//   sf=2             disk cell = sf × the frustum cell's size (per axis)
//   depth=1000       frustum depth in metres used for the cells and culling (capped by the lens)
//   cache=1          index cache, MiB (Optimal, NP)
//   policy=dplru     index cache policy: dplru | lru
//   buffer=0         object buffer, MiB; 0 = whatever --budget leaves (unbounded without one)
//   prefetch=sync    sync (between frames, deterministic) | background (the store's Prefetcher)
//   trigger=0.5      prefetch when the frustum cell is within trigger × its margin of the border
//   fps=30           only for callers that give no path time (stats.time not increasing): the
//                    frame interval is then taken as 1/fps
//   cull=exact       exact (ViewCulling, two-level) | none (draw the whole buffer)
// e.g. "review:k=1.2,sf=1.5" or "review-box:sf=3".
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/index/rtree.hpp"
#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

struct ReviewConfig {
  enum class Variant { kOptimal, kNoCache, kNoPrefetch, kBox };
  Variant variant = Variant::kOptimal;
  double k = 0.8;
  double scale_factor = 2.0;
  double depth = 1000.0;
  uint64_t index_cache_bytes = 1 << 20;
  RTreeCacheOptions::Policy policy = RTreeCacheOptions::Policy::kDistancePriorityLru;
  uint64_t object_buffer_bytes = 0;
  bool background_prefetch = false;
  double trigger = 0.5;
  double fps = 30.0;
  bool cull = true;

  bool complement() const { return variant != Variant::kBox; }
  bool cached() const { return variant == Variant::kOptimal || variant == Variant::kNoPrefetch; }
  bool prefetch() const { return variant == Variant::kOptimal || variant == Variant::kNoCache; }
};

// Whether `name` names a REVIEW configuration (starts with "review").
bool is_review_strategy_name(const std::string& name);
// Parses a name as above. Throws Error naming the bad part.
ReviewConfig parse_review_strategy_name(const std::string& name);

// One disk query (demand or prefetch), for the thesis's per-query measures.
struct ReviewQuery {
  uint64_t frame = 0;
  bool prefetch = false;
  Aabb cell;                  // what was queried
  Aabb predicted;             // prefetches: the thesis's cell, SF × the frustum cell centred on
                              // F' = F + k·v; `cell` is its union with the frustum cell then
  size_t history_cells = 0;   // after the history filter
  uint64_t node_visits = 0, node_reads = 0;  // R-tree pages looked at / read from the file
  uint64_t results = 0;       // objects the search returned
  uint64_t already_buffered = 0;  // results that were buffered already (0 for CSearch: tested)
  uint64_t fetched = 0;       // of those, read and decoded (not already buffered)
  uint64_t object_pages = 0;  // pages of the world file those objects span
  uint64_t dropped = 0;       // results not fetched: the first the buffer refused and all farther
  uint64_t evictions = 0;     // buffer evictions (Fig. 4.8) during the query
  double search_ms = 0, io_ms = 0, decode_ms = 0;
  uint64_t disk_ios() const { return node_reads + object_pages; }
};

// What ViewCulling did in one frame (thesis Table 4.2).
struct ReviewFrame {
  uint64_t buffered = 0;       // objects in the object buffer
  uint64_t drawn = 0;          // objects that passed culling
  uint64_t drawn_triangles = 0, buffered_triangles = 0;
  double cull_ms = 0;
  bool queried = false;        // a demand query ran in this frame
  bool adopted = false;        // the prefetched cell became the disk cell (no demand query)
};

class ReviewStrategy : public Strategy {
 public:
  // Throws Error if the world has no R-tree or the budget cannot hold the directory, the index
  // cache and the largest object. REQUIRES: `world` outlives the strategy.
  ReviewStrategy(const World& world, const ReviewConfig& config, const StrategyOptions& options);
  ~ReviewStrategy() override;

  std::string name() const override;
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  uint64_t resident_bytes() const override;
  uint64_t peak_resident_bytes() const override;

  const ReviewConfig& config() const;
  // Every query so far, in the order they were issued (prefetches: when merged).
  QueryTotals query_totals() const override;  // ms: search, I/O and decode of each query
  const std::vector<ReviewQuery>& queries() const;
  const std::vector<ReviewFrame>& frames() const;
  // Objects a merged prefetch brought that were buffered meanwhile (must stay 0: a demand
  // query first waits for and merges any prefetch in flight).
  uint64_t duplicate_fetches() const;

  // For tests: called after every search (demand or prefetch) with its query so far (cell,
  // history, node counts, results) and the ids it returned, before anything is fetched, on the
  // thread that ran the search (the caller's, except with prefetch=background).
  using SearchObserver = std::function<void(const ReviewQuery&, std::span<const uint32_t> results)>;
  void set_search_observer(SearchObserver observer);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
