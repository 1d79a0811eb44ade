// REVIEW (HDoV thesis chapter 4; digest §3.1–§3.6, §5.4): the two-cell scheme (§4.1), CSearch
// against the history of queried cells (§4.2.2), the R-tree node cache (§4.2.4), prefetching at
// F' = F + k·v (§4.2.5) and ViewCulling of the object buffer (§4.3). docs/review.md.
#include <algorithm>

#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/store/prefetcher.hpp"
#include "cellwalk/systems/review/review.hpp"
#include "core/stopwatch.hpp"
#include "systems/review/review_object_buffer.hpp"
#include "systems/review/review_view_culling.hpp"

namespace cellwalk {

using review::BufferedObject;
using review::ConvexCell;
using review::FetchCounters;
using review::ObjectBuffer;

namespace {

Aabb box_around(const Vec3& centre, const Vec3& size) { return Aabb{centre - size * 0.5f, centre + size * 0.5f}; }

RTreeCacheOptions cache_options(const ReviewConfig& c) {
  RTreeCacheOptions o;
  o.policy = c.cached() ? c.policy : RTreeCacheOptions::Policy::kNone;
  o.bytes = c.index_cache_bytes;
  return o;
}

// A prefetched cell's query, run by the Prefetcher (a worker thread, or between frames).
struct PrefetchedCell {
  struct Payload {
    ReviewQuery query;
    bool complete = true;
    std::vector<BufferedObject> objects;
  };
  std::shared_ptr<Payload> payload;  // mutable behind the cache's const handle
};

// What the strategy holds beside the index cache and the object buffer, at most (docs/review.md,
// "Memory"): the world's directory; a search's path of nodes outside the cache (every node
// without one) and the raw page being decoded; a search's result list (at most every object, at
// most twice its size); one prefetch in flight — its request and loader, its staged entry and
// payload, the heap blocks of its list of buffered ids (whose slots the objects pay for), an
// estimate — and the group a query has begun before any object is in it.
uint64_t fixed_bytes_of(const World& world, const DiskRTree& tree) {
  constexpr uint64_t kPrefetchBytes = sizeof(PrefetchRequest) + sizeof(PrefetchedCell::Payload) + 4 * sizeof(Aabb) +
                                      32 * sizeof(void*) + 16 * kHeapBlockBytes;
  return world.resident_bytes() + tree.height() * rtree_node_resident_bound(tree) + tree.page_size() +
         2 * world.object_count() * sizeof(uint32_t) + kHeapBlockBytes + kPrefetchBytes +
         2 * sizeof(ObjectBuffer::Group);
}

void add_fetch(ReviewQuery& q, const FetchCounters& f) {
  q.fetched += f.fetched;
  q.object_pages += f.pages;
  q.io_ms += f.io_ms;
  q.decode_ms += f.decode_ms;
}

// Fetch order of a query's results: nearest the viewpoint first (squared distance from `eye` to
// each object's box, ties by id). The thesis fetches in search order; when a result does not fit
// the budget the rest is dropped, and dropping the farthest objects costs the picture least
// (docs/review.md, "Under a budget").
void nearest_first(const World& world, const Vec3& eye, std::vector<uint32_t>& ids) {
  auto distance2 = [&](uint32_t id) {
    const Aabb& b = world.object(id).bounds;
    const Vec3 d = glm::max(glm::max(b.min - eye, eye - b.max), Vec3(0.0f));
    return glm::dot(d, d);
  };
  // Sorted in place, distances recomputed: no transient the budget would have to charge.
  std::sort(ids.begin(), ids.end(), [&](uint32_t a, uint32_t b) {
    const float da = distance2(a), db = distance2(b);
    return da < db || (da == db && a < b);
  });
}

}  // namespace

struct ReviewStrategy::Impl {
  Impl(const World& w, const ReviewConfig& c, const StrategyOptions& options)
      : world(w),
        config(c),
        tree(w),
        fixed_bytes(fixed_bytes_of(w, tree)),
        cache(tree, cache_options(c)),
        buffer(object_limit(options)),
        staging(staging_budget, make_lru_policy()),
        prefetcher(staging, PrefetcherOptions{c.background_prefetch ? 1u : 0u, 1}) {}

  // The object buffer's share of the budget: what the fixed part (fixed_bytes_of) and the index
  // cache leave (or the configured size, which must fit).
  uint64_t object_limit(const StrategyOptions& options) const {
    uint64_t largest = 0;
    for (ObjectId id = 0; id < world.object_count(); ++id) largest = std::max(largest, review::fetch_bound(world, id));
    const uint64_t index = cache.limit_bytes();
    const uint64_t b = options.memory_budget_bytes;
    const uint64_t need = fixed_bytes + index + std::max(largest, config.object_buffer_bytes);
    if (b != 0 && b < need)
      fail(world.file().path(), "memory budget of " + byte_size_text(b) + " is too small for REVIEW: the "
                                "directory, the index cache and " +
                                    std::string(config.object_buffer_bytes ? "the object buffer" : "the largest object") +
                                    " need " + byte_size_text(need) + "; give a larger --budget");
    if (config.object_buffer_bytes) {
      if (config.object_buffer_bytes < largest)
        fail(world.file().path(), "object buffer of " + std::to_string(config.object_buffer_bytes) +
                                      " bytes cannot hold the largest object (" + std::to_string(largest) + " bytes)");
      return config.object_buffer_bytes;
    }
    return b == 0 ? 0 : b - fixed_bytes - index;
  }

  double depth(const Camera& camera) const { return std::min<double>(config.depth, camera.far_plane); }

  // Each part's exact peak, summed: an upper bound of the whole's peak, within the budget.
  uint64_t peak() const { return fixed_bytes + cache.peak_bytes() + buffer.budget().peak(); }
  uint64_t resident() const { return fixed_bytes + cache.resident_bytes() + buffer.budget().used(); }

  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats);
  void update_velocity(const Camera& camera, double time);
  void leave_disk_cell(const Aabb& frustum, FrameStats& stats, ReviewFrame& record);
  void make_disk_cell(const Aabb& cell, const Aabb& frustum);
  bool near_border(const Aabb& frustum) const;
  void demand_query(const Aabb& cell, FrameStats& stats);
  bool record_cell(const Aabb& cell, ReviewQuery& q);
  void start_prefetch(const Camera& camera, const Aabb& frustum, FrameStats& stats);
  void merge_prefetches(FrameStats& stats);
  void settle_prefetch(FrameStats& stats);
  void rethrow_prefetch_failure();
  void drop_prefetch();
  void cull(const ConvexCell& h, std::vector<DrawItem>& items, ReviewFrame& frame);
  void count_io(const ReviewQuery& q, FrameStats& stats) const;

  const World& world;
  const ReviewConfig config;
  DiskRTree tree;
  const uint64_t fixed_bytes;  // fixed_bytes_of(): the directory, a search's transients, a prefetch
  RTreeNodeCache cache;
  ObjectBuffer buffer;
  MemoryBudget staging_budget{0};  // prefetched cells cost nothing here: their objects are
  BufferManager staging;           // reserved in the object buffer's budget by the job
  Prefetcher prefetcher;           // last: destroyed first, while what its jobs use exists

  std::optional<Aabb> disk_cell;
  Vec3 margin{0.0f};  // per axis, how far the frustum cell could move inside the new disk cell
  struct Next {
    CacheKey key = 0;
    Aabb cell;
    uint64_t epoch = 0;
    bool merged = false, complete = false;
  };
  std::optional<Next> next;             // the prefetched disk cell
  std::vector<CacheKey> outstanding;    // submitted prefetches not merged or discarded yet
  CacheKey next_key = 1;
  uint64_t failures_seen = 0;           // Prefetcher failures already reported
  std::optional<Vec3> last_position;
  double last_time = 0.0;
  Vec3 velocity{0.0f};
  uint64_t frame = 0;
  std::vector<ReviewQuery> queries;
  std::vector<ReviewFrame> frames;
  uint64_t duplicates = 0;
  SearchObserver observer;
};

void ReviewStrategy::Impl::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Stopwatch watch;
  const double io_before = stats.io_ms, decode_before = stats.decode_ms;
  ++frame;
  update_velocity(camera, stats.time);
  merge_prefetches(stats);
  const ConvexCell h = review::frustum_cell(camera, float(depth(camera)));
  const Aabb frustum = h.bounds();
  ReviewFrame record;
  if (!disk_cell || !disk_cell->contains(frustum)) {
    const size_t before = queries.size();
    leave_disk_cell(frustum, stats, record);
    record.queried = queries.size() > before;
  } else if (config.prefetch() && !next && near_border(frustum)) {
    start_prefetch(camera, frustum, stats);
  }
  cull(h, items, record);
  frames.push_back(record);
  stats.query_ms += std::max(0.0, watch.ms() - (stats.io_ms - io_before) - (stats.decode_ms - decode_before));
}

// v in metres per second of path time. The walk harness passes each frame's PathFrame::time in
// stats.time, so any path (any frame spacing, frames skipped by compare) gives the true speed;
// a caller without times (stats.time not increasing) gets frames 1/fps apart.
void ReviewStrategy::Impl::update_velocity(const Camera& camera, double time) {
  if (last_position) {
    const double dt = time > last_time ? time - last_time : 1.0 / config.fps;
    velocity = (camera.position - *last_position) / float(dt);
  }
  last_position = camera.position;
  last_time = time;
}

// §4.1: the frustum cell left the disk cell. The prefetched cell becomes the disk cell if it
// holds the frustum cell (§4.2.5's chain); otherwise a new disk cell is centred on the frustum
// cell and queried.
void ReviewStrategy::Impl::leave_disk_cell(const Aabb& frustum, FrameStats& stats, ReviewFrame& record) {
  settle_prefetch(stats);
  if (next && next->merged && next->cell.contains(frustum)) {
    const Next taken = *next;
    next.reset();
    make_disk_cell(taken.cell, frustum);
    record.adopted = true;
    if (!taken.complete) demand_query(taken.cell, stats);  // fetch what did not fit then
    return;
  }
  drop_prefetch();
  const Aabb cell = box_around(frustum.center(), frustum.size() * float(config.scale_factor));
  make_disk_cell(cell, frustum);
  demand_query(cell, stats);
}

void ReviewStrategy::Impl::make_disk_cell(const Aabb& cell, const Aabb& frustum) {
  disk_cell = cell;
  margin = glm::max(Vec3(0.0f), (cell.size() - frustum.size()) * 0.5f);
}

// "Approaching the boundary" (§4.2.5, a [GAP]): on some axis the frustum cell has used up more
// than (1 - trigger) of its margin on the side it moves towards (both sides when it does not
// move along that axis). A disk cell with no margin (SF 1) prefetches at once.
bool ReviewStrategy::Impl::near_border(const Aabb& frustum) const {
  for (int a = 0; a < 3; ++a) {
    const float low = frustum.min[a] - disk_cell->min[a], high = disk_cell->max[a] - frustum.max[a];
    const float gap = velocity[a] > 0.0f ? high : velocity[a] < 0.0f ? low : std::min(low, high);
    if (gap <= float(config.trigger) * margin[a]) return true;
  }
  return false;
}

void ReviewStrategy::Impl::count_io(const ReviewQuery& q, FrameStats& stats) const {
  stats.io_ms += q.io_ms;
  stats.decode_ms += q.decode_ms;
  stats.bytes_read += q.node_reads * tree.page_size();
  stats.cache_misses += q.fetched;
}

// A demand query of `cell`: CSearch against the filtered history (or a plain box search for
// BOX, whose buffer is replaced), every result read and decoded into the buffer. When the budget
// refuses an object, the buffer keeps only what overlaps `cell` and the history is cut back
// (Fig. 4.8 and the digest's fix); the cell enters the history only if everything fitted.
void ReviewStrategy::Impl::demand_query(const Aabb& cell, FrameStats& stats) {
  settle_prefetch(stats);  // never search or fetch beside a prefetch in flight
  ReviewQuery q;
  q.frame = frame;
  q.cell = cell;
  Stopwatch watch;
  std::vector<Aabb> history;
  if (config.complement()) history = buffer.filtered_history(cell);
  else buffer.clear();
  q.history_cells = history.size();
  std::vector<uint32_t> ids;
  SearchCounters sc;
  complement_search(cache, cell, history, ids, sc);
  q.search_ms = watch.ms();
  q.node_visits = sc.node_visits;
  q.node_reads = sc.node_reads;
  q.results = ids.size();
  if (observer) observer(q, ids);
  nearest_first(world, last_position.value_or(cell.center()), ids);
  buffer.begin_group(cell);
  FetchCounters fc;
  for (size_t i = 0; i < ids.size(); ++i) {
    const uint32_t id = ids[i];
    if (buffer.contains(id)) {  // left by an incomplete query: not fetched again
      ++q.already_buffered;
      continue;
    }
    std::optional<BufferedObject> o = review::fetch_object(world, id, buffer.budget(), fc);
    if (!o && config.complement()) {
      ++q.evictions;
      buffer.evict_outside(std::span<const Aabb>(&cell, 1));
      drop_prefetch();
      o = review::fetch_object(world, id, buffer.budget(), fc);
    }
    if (!o) {  // the rest is farther (nearest_first): dropped, so the buffer holds a nearest prefix
      q.dropped = ids.size() - i;
      break;
    }
    buffer.insert(std::move(*o));
  }
  if (q.dropped == 0 && config.complement()) record_cell(cell, q);
  add_fetch(q, fc);
  stats.stall = stats.stall || q.dropped > 0;
  count_io(q, stats);
  queries.push_back(q);
}

// Enters a completed query's cell in the history. When the budget has no room for it, what does
// not overlap the cell is evicted first, as for an object that does not fit; a cell still left
// out only makes later searches return objects that are buffered (counted, not fetched).
bool ReviewStrategy::Impl::record_cell(const Aabb& cell, ReviewQuery& q) {
  if (buffer.record_cell(cell)) return true;
  ++q.evictions;
  buffer.evict_outside(std::span<const Aabb>(&cell, 1));
  drop_prefetch();
  return buffer.record_cell(cell);
}

// §4.2.5: the next disk cell, SF × the frustum cell centred on the far plane's centre moved by
// k·velocity, united with the current frustum cell (a deviation, docs/review.md: the thesis's
// cell alone lies so far ahead that for SF < 1.67, or walking backwards with k·v below the
// trigger's slack, the frustum cell leaving the disk cell is never inside it). Queried with
// CSearch against the (filtered) history; in deterministic mode it runs now, between frames.
void ReviewStrategy::Impl::start_prefetch(const Camera& camera, const Aabb& frustum, FrameStats& stats) {
  const Vec3 far_centre = camera.position + camera.forward() * float(depth(camera));
  const Aabb predicted =
      box_around(far_centre + velocity * float(config.k), frustum.size() * float(config.scale_factor));
  Aabb cell = predicted;
  cell.extend(frustum);
  next = Next{next_key++, cell, buffer.eviction_epoch(), false, false};
  outstanding.push_back(next->key);
  auto history = std::make_shared<const std::vector<Aabb>>(buffer.filtered_history(cell));
  // Freed by the loader before it returns: the objects pay for its slots, and none is evicted
  // while it runs (a demand query first waits for the prefetch).
  auto buffered = std::make_shared<const std::vector<ObjectId>>(buffer.buffered_ids());
  const uint64_t at_frame = frame;
  PrefetchRequest request;
  request.key = next->key;
  request.epoch = frame;
  const Vec3 eye = camera.position + velocity * float(config.k);  // where the viewer is expected
  request.loader = [this, cell, predicted, eye, history, buffered, at_frame]() mutable -> LoadedItem {
    auto payload = std::make_shared<PrefetchedCell::Payload>();
    ReviewQuery& q = payload->query;
    q.frame = at_frame;
    q.prefetch = true;
    q.cell = cell;
    q.predicted = predicted;
    q.history_cells = history->size();
    Stopwatch watch;
    std::vector<uint32_t> ids;
    SearchCounters sc;
    complement_search(cache, cell, *history, ids, sc);
    q.search_ms = watch.ms();
    q.node_visits = sc.node_visits;
    q.node_reads = sc.node_reads;
    q.results = ids.size();
    if (observer) observer(q, ids);
    nearest_first(world, eye, ids);
    FetchCounters fc;
    for (size_t i = 0; i < ids.size(); ++i) {
      if (std::binary_search(buffered->begin(), buffered->end(), ids[i])) {
        ++q.already_buffered;
        continue;
      }
      std::optional<BufferedObject> o = review::fetch_object(world, ids[i], buffer.budget(), fc);
      if (!o) {  // the buffer is full: the rest is fetched if this cell becomes the disk cell
        payload->complete = false;
        q.dropped = ids.size() - i;
        break;
      }
      payload->objects.push_back(std::move(*o));
    }
    add_fetch(q, fc);
    buffered.reset();
    history.reset();
    return {std::make_shared<const PrefetchedCell>(PrefetchedCell{payload}), 0};
  };
  prefetcher.submit(std::move(request));
  if (!config.background_prefetch) {
    prefetcher.run_until_idle();
    merge_prefetches(stats);
  }
}

// Takes finished prefetches into the buffer. A prefetch that is no longer the pending one is
// discarded (its reservations released); one that raced an eviction cannot enter the history.
void ReviewStrategy::Impl::merge_prefetches(FrameStats& stats) {
  rethrow_prefetch_failure();
  std::erase_if(outstanding, [&](CacheKey key) {
    if (!staging.contains(key)) return false;
    std::shared_ptr<PrefetchedCell::Payload> payload;
    {
      const CacheResult r = staging.get(key, EntryMeta{}, [] () -> LoadedItem { fail("review", "internal: prefetch lost"); });
      payload = BufferManager::get_as<PrefetchedCell>(r)->payload;
    }
    staging.erase(key);
    if (!next || next->key != key) return true;
    buffer.begin_group(next->cell);
    for (BufferedObject& o : payload->objects)
      if (!buffer.insert(std::move(o))) ++duplicates;
    next->merged = true;
    // Not in the history (then queried again if adopted) if it raced an eviction, did not fit,
    // or the budget has no room for the history entry.
    next->complete =
        payload->complete && next->epoch == buffer.eviction_epoch() && buffer.record_cell(next->cell);
    if (!config.background_prefetch) count_io(payload->query, stats);
    queries.push_back(payload->query);
    return true;
  });
}

// A demand query must not run beside a background prefetch (both would fetch the same objects,
// search with one reserved path of node pages, and re-score DPLRU under each other): wait for
// the prefetch in flight and merge it first. The wait is I/O the frame stalls on.
void ReviewStrategy::Impl::settle_prefetch(FrameStats& stats) {
  if (outstanding.empty() || !config.background_prefetch) return;
  Stopwatch wait;
  prefetcher.wait_idle();
  stats.io_ms += wait.ms();
  merge_prefetches(stats);
}

// The Prefetcher catches a loader's exception and counts it; a failed prefetch never reaches
// staging, so it is reported here, on the walk's thread, with its key forgotten.
void ReviewStrategy::Impl::rethrow_prefetch_failure() {
  const PrefetchStats ps = prefetcher.stats();
  if (ps.failed == failures_seen) return;
  failures_seen = ps.failed;
  if (config.background_prefetch) prefetcher.wait_idle();
  for (CacheKey key : outstanding) staging.erase(key);
  outstanding.clear();
  next.reset();
  fail(world.file().path(), "REVIEW prefetch failed: " + ps.last_error);
}

void ReviewStrategy::Impl::drop_prefetch() {
  if (next && !next->merged && prefetcher.cancel(next->key)) std::erase(outstanding, next->key);
  next.reset();
}

// §4.3: two-level ViewCulling — a retrieved cell's objects are skipped together when the cell's
// box misses the frustum, else each object's box is tested.
void ReviewStrategy::Impl::cull(const ConvexCell& h, std::vector<DrawItem>& items, ReviewFrame& record) {
  Stopwatch watch;
  items.clear();
  for (const ObjectBuffer::Group& g : buffer.groups()) {
    record.buffered += g.members.size();
    for (ObjectId id : g.members) record.buffered_triangles += buffer.object(id).mesh->triangle_count();
    if (config.cull && !review::view_culling_overlaps(h, g.bounds)) continue;
    for (ObjectId id : g.members) {
      const BufferedObject& o = buffer.object(id);
      if (config.cull && !review::view_culling_overlaps(h, o.box)) continue;
      items.push_back({id, 0, world.object(id).color});
      ++record.drawn;
      record.drawn_triangles += o.mesh->triangle_count();
    }
  }
  record.cull_ms = watch.ms();
}

ReviewStrategy::ReviewStrategy(const World& world, const ReviewConfig& config, const StrategyOptions& options)
    : impl_(std::make_unique<Impl>(world, config, options)) {}

ReviewStrategy::~ReviewStrategy() = default;

std::string ReviewStrategy::name() const {
  switch (impl_->config.variant) {
    case ReviewConfig::Variant::kNoCache: return "review-nc";
    case ReviewConfig::Variant::kNoPrefetch: return "review-np";
    case ReviewConfig::Variant::kBox: return "review-box";
    case ReviewConfig::Variant::kOptimal: break;
  }
  return "review";
}

void ReviewStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  impl_->select(camera, items, stats);
}

const Mesh* ReviewStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  const Mesh* mesh = impl_->buffer.mesh(item.id);
  ++(mesh ? stats.cache_hits : stats.cache_misses);
  return mesh;
}

uint64_t ReviewStrategy::resident_bytes() const { return impl_->resident(); }
uint64_t ReviewStrategy::peak_resident_bytes() const { return impl_->peak(); }
const ReviewConfig& ReviewStrategy::config() const { return impl_->config; }
const std::vector<ReviewQuery>& ReviewStrategy::queries() const { return impl_->queries; }

QueryTotals ReviewStrategy::query_totals() const {
  QueryTotals t{.queries = impl_->queries.size()};
  for (const ReviewQuery& q : impl_->queries) t.disk_ios += q.disk_ios(), t.ms += q.search_ms + q.io_ms + q.decode_ms;
  return t;
}
const std::vector<ReviewFrame>& ReviewStrategy::frames() const { return impl_->frames; }
uint64_t ReviewStrategy::duplicate_fetches() const { return impl_->duplicates; }
void ReviewStrategy::set_search_observer(SearchObserver observer) { impl_->observer = std::move(observer); }

}  // namespace cellwalk
