// Li & Chiang (seed 003): "Visibility Pre-computation", "Prioritized Spatial Prefetching",
// "Data Caching: Hybrid Cache Model" (cellwalk/systems/lichiang/lichiang_strategy.hpp).
#include "cellwalk/systems/lichiang/lichiang_strategy.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <unordered_map>
#include <unordered_set>

#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/store/prefetcher.hpp"
#include "cellwalk/systems/lichiang/configurations.hpp"
#include "cellwalk/systems/lichiang/relevance.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "core/stopwatch.hpp"
#include "strategy/strategy_config.hpp"

namespace cellwalk {

bool is_lichiang_strategy_name(const std::string& name) {
  return name == "lichiang" || name.rfind("lichiang:", 0) == 0;
}

namespace {

// A setting's number as the name gives it back (shortest form: 5, 2.5, 1e-05).
std::string number_text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

}  // namespace

LiChiangConfig parse_lichiang_strategy_name(const std::string& name) {
  if (!is_lichiang_strategy_name(name))
    fail("strategy \"" + name + "\"", "not a Li-Chiang name (lichiang[:key=value,...])");
  LiChiangConfig c;
  for_each_strategy_setting(name, [&](const StrategySetting& s) {
    if (s.key == "cache") {
      s.choice({"none", "lru", "hybrid"});
      c.cache = s.value == "none" ? LiChiangConfig::Cache::kNone
                : s.value == "lru" ? LiChiangConfig::Cache::kLru : LiChiangConfig::Cache::kHybrid;
    } else if (s.key == "prefetch") {
      s.choice({"none", "one-step", "relevance"});
      c.prefetch = s.value == "none" ? LiChiangConfig::Prefetch::kNone
                   : s.value == "one-step" ? LiChiangConfig::Prefetch::kOneStep : LiChiangConfig::Prefetch::kRelevance;
    } else if (s.key == "sectors") c.sectors = s.whole(1, 64);
    else if (s.key == "neighbours") c.neighbours = s.whole(0, 1) != 0;
    else if (s.key == "cull") c.cull = s.whole(0, 1) != 0;
    else if (s.key == "tp_ms") c.tp_ms = s.number(0, 1e6);
    else if (s.key == "frame_ms") c.frame_ms = s.number(0, 1e6);
    else s.unknown("cache, prefetch, sectors, neighbours, cull, tp_ms, frame_ms");
  });
  if (c.tp_ms >= 0 && c.frame_ms >= 0)
    fail("strategy \"" + name + "\"", "give tp_ms (a fixed prefetch time) or frame_ms (t_p = frame_ms - t_c - t_g), not both");
  if (c.prefetch_in_frame() && c.prefetch == LiChiangConfig::Prefetch::kNone)
    fail("strategy \"" + name + "\"", "tp_ms and frame_ms set the time for prefetching; with prefetch=none there is none");
  if (c.cache == LiChiangConfig::Cache::kNone && c.prefetch != LiChiangConfig::Prefetch::kNone)
    fail("strategy \"" + name + "\"", "cache=none keeps nothing, so it has nowhere to prefetch into; add prefetch=none (the seed's case 1)");
  return c;
}

namespace {

using Prefetch = LiChiangConfig::Prefetch;

// The configurations' positions are a grid (the relevance matrix's neighbours are grid steps).
visibility::StoredPvs open_sets(const World& world) {
  if (!world.file().has_section(visibility::kPvsSection))
    fail(world.file().path(), "has no visible sets for lichiang; run `cellwalk pvs " + world.file().path() +
                                  " --cells grid:SIZE` first (any engine but vlod)");
  visibility::StoredPvs pvs(world);
  if (pvs.partition().kind() != "grid")
    fail(world.file().path(), "its visible sets are over " + pvs.partition().kind() +
                                  " cells, and lichiang's configurations step over a grid; rerun `cellwalk pvs " +
                                  world.file().path() + " --cells grid:SIZE`");
  return pvs;
}

double signed_angle(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

// What makes a prefetch plan: when none of it changes, the queued plan still holds.
struct PlanKey {
  CellId cell = 0;
  int sector = 0;
  int octant = 0;      // the heading's nearest grid direction: where the window and one step go
  int shift = 0;       // ⌈ν⌉
  long omega = 0;      // ω in steps of 0.05 rad per frame
  bool operator==(const PlanKey&) const = default;
};

// The bytes a decoded set of `ids` holds, with its map node.
uint64_t set_bytes(const std::vector<ObjectId>& ids) { return ids.capacity() * sizeof(ObjectId) + 64; }

}  // namespace

struct LiChiangStrategy::Impl {
  Impl(const World& w, const LiChiangConfig& c, const StrategyOptions& o)
      : world(w),
        config(c),
        options(o),
        pvs(open_sets(w)),
        store(w, o.memory_budget_bytes,
              c.cache == LiChiangConfig::Cache::kHybrid ? make_hybrid_relevance_policy() : make_lru_policy(),
              c.prefetch != Prefetch::kNone ? 2 : 1, open_level_source(w, o.objects_db)),
        // One loader thread, one load at a time: the store keeps room for it beside get()'s. In
        // the seed's cycle (tp_ms, frame_ms) the frame's thread steps it instead.
        prefetcher(store.buffer(), PrefetcherOptions{c.prefetch != Prefetch::kNone && !c.prefetch_in_frame() ? 1u : 0u, 1}) {
    pvs_bytes = pvs.resident_bytes();
    if (!store.buffer().budget().try_reserve(pvs_bytes))
      fail(w.file().path(), "memory budget of " + byte_size_text(o.memory_budget_bytes) +
                                " cannot hold the stored visible sets (" + byte_size_text(pvs_bytes) +
                                ") beside the directory and the loads in flight; give a larger --budget");
  }
  // The loader thread stops before the bytes it could admit into are released.
  ~Impl() {
    prefetcher.cancel_older_than(UINT64_MAX);
    if (config.prefetch != Prefetch::kNone && !config.prefetch_in_frame()) prefetcher.wait_idle();
    sets.clear();
    store.buffer().budget().release(pvs_bytes + sets_bytes);
  }

  const World& world;
  LiChiangConfig config;
  StrategyOptions options;
  visibility::StoredPvs pvs;
  GeometryStore store;
  uint64_t pvs_bytes = 0;
  // Decoded sets of the cells the frames draw from, each charged to the budget as it is decoded
  // (sets_bytes in all); those of cells no frame drew from since are freed at the frame's end.
  std::unordered_map<CellId, std::vector<ObjectId>> sets;
  std::unordered_set<CellId> touched;
  uint64_t sets_bytes = 0;
  std::optional<Camera> last;  // the previous frame's camera: ν and ω
  std::optional<CellId> cell;
  int sector = 0;
  uint64_t frame = 0;  // the frame select() chose last: the hybrid cache's clock
  std::optional<PlanKey> planned;
  std::vector<CacheKey> used;  // cache=none: what the last frame read, dropped before the next
  LiChiangCounters counters;
  std::shared_ptr<const Mesh> current;  // the mesh handed to the renderer for upload
  std::optional<Stopwatch> work;        // since the last frame's t_p ended: its t_c + t_g
  Prefetcher prefetcher;                // last: destroyed first, while what its jobs use exists

  // t_p in the seed's cycle, run when the next frame begins: the fixed allowance, or what the
  // frame budget leaves of the last frame's t_c + t_g (nothing before the first frame).
  void prefetch_in_frame() {
    double tp = config.tp_ms;
    if (config.frame_ms >= 0.0) tp = work ? std::max(0.0, config.frame_ms - work->ms()) : 0.0;
    Stopwatch spent;
    prefetcher.step_for(tp);
    counters.prefetch_ms += spent.ms();
    work.emplace();
  }

  const ViewCellPartition& cells() const { return pvs.partition(); }
  // Objects drawn are the most relevant of their frame (w = c).
  EntryMeta drawn_meta() const { return EntryMeta{.relevance = float(lichiang::RelevanceParams{}.c), .frame = frame}; }

  // Charges `bytes` more, evicting cached geometry if it must.
  void charge(uint64_t bytes, CellId c) {
    if (!store.buffer().reserve(bytes))
      fail("lichiang", "memory budget of " + byte_size_text(options.memory_budget_bytes) + " cannot hold the set of cell " +
                           std::to_string(c) + " (" + byte_size_text(bytes) + ") beside " + std::to_string(sets.size()) +
                           " others; give a larger --budget");
    sets_bytes += bytes;
  }

  // The stored set of cell `c`, decoded and kept (charged) until no frame draws from it.
  const std::vector<ObjectId>& set_of(CellId c) {
    touched.insert(c);
    auto it = sets.find(c);
    if (it != sets.end()) return it->second;
    std::optional<VisibleSet> s = pvs.set(c);
    std::vector<ObjectId> ids = s ? std::move(s->objects) : std::vector<ObjectId>{};
    charge(set_bytes(ids), c);
    return sets.emplace(c, std::move(ids)).first->second;
  }

  // The cell `dx`, `dz` cells from the current one along x and z, if it has a set.
  std::optional<CellId> offset_cell(int dx, int dz) const {
    const Aabb& box = cells().cell(*cell).box;
    const Vec3 size = box.max - box.min;
    const Vec3 p = box.center() + Vec3(float(dx) * size.x, 0.0f, float(dz) * size.z);
    const std::optional<CellId> c = cells().locate(p);
    if (!c || !cells().cell(*c).computed()) return std::nullopt;
    return c;
  }

  // Adds the objects of configuration (c, directions) in `ids` to `out`, skipping those in `seen`.
  void add_configuration(CellId c, const std::vector<ObjectId>& ids, const lichiang::YawRange& directions,
                         std::vector<ObjectId>& out, std::unordered_set<ObjectId>& seen) const {
    const Aabb& box = cells().cell(c).box;
    for (ObjectId id : ids)
      if (!seen.contains(id) && lichiang::directions_between(box, world.object(id).bounds).meets(directions)) {
        seen.insert(id);
        out.push_back(id);
      }
  }
  void add_configuration(CellId c, const lichiang::YawRange& directions, std::vector<ObjectId>& out,
                         std::unordered_set<ObjectId>& seen) {
    add_configuration(c, set_of(c), directions, out, seen);
  }
  // For planning: the set of a cell the frame does not draw from is decoded, charged while it is
  // used and freed at once.
  void add_planned_configuration(CellId c, const lichiang::YawRange& directions, std::vector<ObjectId>& out,
                                 std::unordered_set<ObjectId>& seen) {
    if (auto it = sets.find(c); it != sets.end()) return add_configuration(c, it->second, directions, out, seen);
    std::optional<VisibleSet> s = pvs.set(c);
    if (!s) return;
    const uint64_t bytes = set_bytes(s->objects);
    charge(bytes, c);
    add_configuration(c, s->objects, directions, out, seen);
    store.buffer().budget().release(bytes);
    sets_bytes -= bytes;
  }

  // Frees the decoded sets no frame drew from this time.
  void settle_sets() {
    for (auto it = sets.begin(); it != sets.end();) {
      if (touched.contains(it->first)) {
        ++it;
        continue;
      }
      const uint64_t bytes = set_bytes(it->second);
      it = sets.erase(it);
      store.buffer().budget().release(bytes);
      sets_bytes -= bytes;
    }
    touched.clear();
  }

  // The union of the sets of the current configuration's 1-neighbours (or its own set).
  std::vector<ObjectId> drawn_set(std::optional<double> margin) {
    std::vector<ObjectId> out;
    std::unordered_set<ObjectId> seen;
    const int reach = config.neighbours ? 1 : 0;
    const lichiang::YawRange own = lichiang::sector_range(sector, 0, config.sectors, margin);
    add_configuration(*cell, own, out, seen);
    counters.own_ids += out.size();
    const lichiang::YawRange around = lichiang::sector_range(sector, reach, config.sectors, margin);
    for (int dx = -reach; dx <= reach; ++dx)
      for (int dz = -reach; dz <= reach; ++dz)
        if (const std::optional<CellId> c = offset_cell(dx, dz)) add_configuration(*c, around, out, seen);
    counters.drawn_ids += out.size();
    return out;
  }

  void submit(ObjectId id, double w, uint64_t frame) {
    const CacheKey key = GeometryStore::key(id, 0);
    if (store.buffer().resident_or_loading(key)) return;
    prefetcher.submit({key, w, frame, EntryMeta{.relevance = float(w), .frame = frame}, store.loader(id, 0)});
    ++counters.prefetch_requests;
  }

  // t_p: the objects of the neighbouring configurations the viewer will want, for the loader
  // thread. Planned again only when the configuration or the motion changes; the old plan's
  // requests not yet started are dropped then.
  void plan_prefetch(const std::vector<ObjectId>& drawn, double nu, double omega, double yaw,
                     std::optional<double> margin, uint64_t frame) {
    const int octant = int(std::lround(yaw / (std::numbers::pi / 4.0))) & 7;
    const PlanKey key{*cell, sector, octant, nu > 0 ? int(std::ceil(nu)) : 0, std::lround(omega / 0.05)};
    if (planned == key) return;
    planned.reset();  // set again once the plan is whole
    prefetcher.cancel_older_than(frame);
    std::unordered_set<ObjectId> seen(drawn.begin(), drawn.end());
    const lichiang::YawRange directions = lichiang::sector_range(sector, 1, config.sectors, margin);
    std::vector<ObjectId> ids;
    if (config.prefetch == Prefetch::kRelevance) {
      for (const lichiang::RelevanceEntry& e : lichiang::relevance_window(nu, omega, yaw)) {
        const std::optional<CellId> c = offset_cell(e.dx, e.dz);
        if (!c) continue;
        ids.clear();
        add_planned_configuration(*c, directions, ids, seen);
        for (ObjectId id : ids) submit(id, e.w, frame);
      }
    } else {  // one step: the configuration the viewer moves into next, and its 1-neighbours
      const double heading = octant * std::numbers::pi / 4.0, step = std::max(1, key.shift);
      const int sx = int(std::lround(-std::sin(heading))) * int(step), sz = int(std::lround(-std::cos(heading))) * int(step);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dz = -1; dz <= 1; ++dz)
          if (const std::optional<CellId> c = offset_cell(sx + dx, sz + dz)) add_planned_configuration(*c, directions, ids, seen);
      for (ObjectId id : ids) submit(id, 0.0, frame);
    }
    planned = key;
    ++counters.plans;
  }
};

LiChiangStrategy::LiChiangStrategy(const World& world, const LiChiangConfig& config, const StrategyOptions& options)
    : impl_(std::make_unique<Impl>(world, config, options)) {}

LiChiangStrategy::~LiChiangStrategy() = default;

std::string LiChiangStrategy::name() const {
  const LiChiangConfig& c = impl_->config;
  const LiChiangConfig d;
  std::string s;
  auto add = [&](const std::string& item) { s += (s.empty() ? "" : ",") + item; };
  if (c.cache != d.cache) add(std::string("cache=") + (c.cache == LiChiangConfig::Cache::kNone ? "none" : "lru"));
  if (c.prefetch != d.prefetch) add(std::string("prefetch=") + (c.prefetch == Prefetch::kNone ? "none" : "one-step"));
  if (c.sectors != d.sectors) add("sectors=" + std::to_string(c.sectors));
  if (c.neighbours != d.neighbours) add("neighbours=0");
  if (c.cull != d.cull) add("cull=0");
  if (c.tp_ms >= 0) add("tp_ms=" + number_text(c.tp_ms));
  if (c.frame_ms >= 0) add("frame_ms=" + number_text(c.frame_ms));
  return s.empty() ? "lichiang" : "lichiang:" + s;
}

// Outside every cell (or in a solid one) no set holds: the frame draws the frustum, as brute.
void LiChiangStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Impl& s = *impl_;
  if (s.config.prefetch_in_frame()) s.prefetch_in_frame();
  Stopwatch watch;
  const uint64_t frame = s.frame = s.counters.frames++;
  if (s.config.cache == LiChiangConfig::Cache::kNone) {
    s.current.reset();  // held, it could not be erased
    for (CacheKey key : s.used) s.store.buffer().erase(key);
    s.used.clear();
  }
  const std::optional<CellId> c = s.cells().locate(camera.position);
  if (c && s.cells().cell(*c).skipped) fail_in_skipped_cell("lichiang", s.cells().cell(*c), camera.position);
  const double yaw = glm::radians(double(camera.yaw_deg));
  const int sector = s.config.sectors == 1 ? 0 : lichiang::sector_of(yaw, s.config.sectors);
  if (c && s.cell && (*c != *s.cell || sector != s.sector)) ++s.counters.configuration_changes;
  s.cell = c && s.cells().cell(*c).computed() ? c : std::nullopt;
  s.sector = sector;
  double nu = 0.0, omega = 0.0;
  if (s.last && s.cell) {
    const Vec3 size = s.cells().cell(*s.cell).box.max - s.cells().cell(*s.cell).box.min;
    nu = std::hypot(camera.position.x - s.last->position.x, camera.position.z - s.last->position.z) /
         std::max(1e-6f, std::min(size.x, size.z));
    omega = signed_angle(glm::radians(double(camera.yaw_deg - s.last->yaw_deg)));
  }
  s.last = camera;
  const std::optional<double> margin = s.config.sectors == 1 ? std::nullopt : lichiang::yaw_half_extent(camera);
  items.clear();
  const Frustum frustum(camera);
  auto add = [&](ObjectId id) {
    const ObjectRecord& o = s.world.object(id);
    if (!s.config.cull || frustum.intersects(o.bounds)) items.push_back({id, 0, o.color});
  };
  if (s.cell) {
    const std::vector<ObjectId> drawn = s.drawn_set(margin);
    for (ObjectId id : drawn) add(id);
    // What this frame draws ranks above anything the loader thread brings meanwhile.
    for (const DrawItem& item : items) s.store.buffer().touch(GeometryStore::key(item.id, item.lod), s.drawn_meta());
    if (s.config.prefetch != Prefetch::kNone) s.plan_prefetch(drawn, nu, omega, yaw, margin, frame);
  } else {
    for (ObjectId id = 0; id < s.world.object_count(); ++id)
      if (frustum.intersects(s.world.object(id).bounds)) add(id);
  }
  s.settle_sets();
  stats.query_ms += watch.ms();
}

// An object neither resident nor prefetched is read now (t_c): the frame stalls on it. Drawn
// objects are the most relevant of their frame.
const Mesh* LiChiangStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  Impl& s = *impl_;
  s.current.reset();  // the renderer has uploaded it: let the store evict it
  const uint64_t misses = stats.cache_misses;
  s.current = s.store.get(item.id, item.lod, s.drawn_meta(), stats);
  stats.stall = stats.stall || stats.cache_misses > misses;
  if (s.config.cache == LiChiangConfig::Cache::kNone) s.used.push_back(GeometryStore::key(item.id, item.lod));
  return s.current.get();
}

uint64_t LiChiangStrategy::resident_bytes() const { return impl_->store.resident_bytes(); }
uint64_t LiChiangStrategy::peak_resident_bytes() const { return impl_->store.peak_resident_bytes(); }
const LiChiangCounters& LiChiangStrategy::counters() const { return impl_->counters; }

}  // namespace cellwalk
