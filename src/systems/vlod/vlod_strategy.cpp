// vLOD's run time (seed 001 §2, §6; digest 001 §3.8): locate the viewer's cell; at each cell
// change apply the Δ from the old vLOD to the new (drop R, load A); prefetch what the face
// neighbours add, asynchronously; draw the vLOD. Nothing is traversed per frame but the vLOD
// itself (optionally frustum-culled, a choice the seed leaves open).
#include "cellwalk/systems/vlod/vlod_strategy.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/lod/screen_error.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/store/prefetcher.hpp"
#include "cellwalk/visibility/cell_lod.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "core/stopwatch.hpp"
#include "strategy/strategy_config.hpp"

namespace cellwalk {

bool is_vlod_strategy_name(const std::string& name) { return name == "vlod" || name.rfind("vlod:", 0) == 0; }

VlodConfig parse_vlod_strategy_name(const std::string& name) {
  if (!is_vlod_strategy_name(name)) fail("strategy \"" + name + "\"", "not a vLOD name (vlod[:key=value,...])");
  VlodConfig c;
  for_each_strategy_setting(name, [&](const StrategySetting& s) {
    if (s.key == "cull") c.cull = s.number(0, 1) != 0;
    else if (s.key == "prefetch") c.prefetch = s.number(0, 1) != 0;
    else s.unknown("cull, prefetch");
  });
  return c;
}

namespace {

constexpr const char* kEnginePrefix = "vlod:";

// One entry of a vLOD: an object at the level its cell draws it (vLOD's "id": a polygon group).
struct Piece {
  ObjectId id;
  uint32_t level;
  auto operator<=>(const Piece&) const = default;
};

const World& with_sets(const World& world) {
  if (!world.file().has_section(visibility::kCellsSection) || !world.file().has_section(visibility::kPvsSection))
    fail(world.file().path(), "has no vLOD sets; run `cellwalk pvs " + world.file().path() + " --engine vlod` first");
  return world;
}

visibility::CellLodRule rule_of(const World& world, const visibility::StoredPvs& pvs) {
  if (pvs.engine().rfind(kEnginePrefix, 0) != 0)
    fail(world.file().path(), "its stored sets come from engine '" + pvs.engine() +
                                  "', not vlod; run `cellwalk pvs " + world.file().path() + " --engine vlod`");
  return visibility::parse_cell_lod_rule(pvs.engine().substr(std::char_traits<char>::length(kEnginePrefix)),
                                         world.file().path() + " section pvs");
}

}  // namespace

struct VlodStrategy::Impl {
  Impl(const World& w, const VlodConfig& c, const StrategyOptions& o)
      : world(w),
        config(c),
        options(o),
        pvs(with_sets(w)),
        rule(rule_of(w, pvs)),
        store(w, o.memory_budget_bytes, nullptr, c.prefetch ? 2 : 1),
        prefetcher(store.buffer(), PrefetcherOptions{c.prefetch ? 1u : 0u, 1}) {
    sets_bytes = pvs.resident_bytes();
    if (!store.buffer().budget().try_reserve(sets_bytes))
      fail(w.file().path(), "memory budget of " + byte_size_text(o.memory_budget_bytes) +
                                " cannot hold the stored vLOD sets (" + byte_size_text(sets_bytes) +
                                ") beside the directory and the loads in flight; give a larger --budget");
  }
  ~Impl() { store.buffer().budget().release(sets_bytes); }

  const World& world;
  VlodConfig config;
  StrategyOptions options;
  visibility::StoredPvs pvs;
  visibility::CellLodRule rule;
  GeometryStore store;
  uint64_t sets_bytes = 0;
  std::optional<CellId> cell;        // the cell whose vLOD `pieces` is; none outside every cell
  std::vector<Piece> pieces;         // ascending
  std::optional<Vec3> last_position;
  VlodCounters counters;
  std::shared_ptr<const Mesh> current;  // the mesh handed to the renderer for upload
  Prefetcher prefetcher;                // last: destroyed first, while what its jobs use exists

  std::vector<Piece> vlod_of(CellId c) const {
    std::vector<Piece> out;
    const std::optional<VisibleSet> set = pvs.set(c);
    if (!set) return out;
    const Aabb& box = pvs.partition().cell(c).box;
    out.reserve(set->objects.size());
    for (ObjectId id : set->objects) out.push_back({id, visibility::cell_level(world, id, box, rule)});
    return out;
  }

  // Cell boundaries between two positions: the cells met at steps of a quarter of the smallest
  // cell side met so far (the seed's "intermediate cells" of a fast move).
  uint64_t boundaries_crossed(const Vec3& from, const Vec3& to) const {
    const ViewCellPartition& cells = pvs.partition();
    std::optional<CellId> at = cells.locate(from);
    uint64_t crossed = 0;
    float t = 0.0f;
    const float length = glm::length(to - from);
    while (t < length) {
      const Vec3 size = at ? cells.cell(*at).box.size() : Vec3(1.0f);
      const float side = std::min({size.x, size.y, size.z});
      t = std::min(length, t + std::max(0.25f * side, 1e-3f));
      const std::optional<CellId> next = cells.locate(from + (to - from) * (t / length));
      if (next != at) ++crossed;
      at = next;
    }
    return crossed;
  }

  void check_lens(const Camera& camera) const {
    const float height = options.viewport_height_px > 0 ? options.viewport_height_px : rule.lens.viewport_height_px;
    if (!visibility::rule_covers(rule, lens_of(camera, height)))
      fail("vlod", "the levels were chosen for " + visibility::to_string(rule) + ", and an image " +
                       std::to_string(int(height)) + " px high at fov " + std::to_string(int(camera.fov_y_deg)) +
                       "° would magnify their error past that bound; render smaller, or rerun "
                       "`cellwalk pvs --engine vlod` with a larger --lod-height or --lod-fov");
  }

  // The Δ to the new cell's vLOD: R is dropped (evictable), A is loaded as it is drawn.
  void enter(CellId c, const Vec3& position, uint64_t frame) {
    std::vector<Piece> next = vlod_of(c);
    std::vector<Piece> added, removed;
    std::set_difference(next.begin(), next.end(), pieces.begin(), pieces.end(), std::back_inserter(added));
    std::set_difference(pieces.begin(), pieces.end(), next.begin(), next.end(), std::back_inserter(removed));
    for (const Piece& p : removed) store.buffer().erase(GeometryStore::key(p.id, p.level));
    ++counters.cell_changes;
    counters.added += added.size();
    counters.removed += removed.size();
    counters.delta_fractions.push_back(next.empty() ? 0.0 : double(added.size() + removed.size()) / double(next.size()));
    pieces = std::move(next);
    cell = c;
    if (config.prefetch) prefetch_neighbours(c, position, frame);
  }

  // §6: the six face Δs' additions, nearest neighbour first; requests of older cells are dropped.
  void prefetch_neighbours(CellId c, const Vec3& position, uint64_t frame) {
    prefetcher.cancel_older_than(frame);
    for (CellId n : pvs.partition().face_neighbours(c)) {
      if (!pvs.partition().cell(n).computed()) continue;
      const double priority = -double(distance_to_box(position, pvs.partition().cell(n).box));
      for (const Piece& p : vlod_of(n)) {
        if (std::binary_search(pieces.begin(), pieces.end(), p)) continue;
        prefetcher.submit({GeometryStore::key(p.id, p.level), priority, frame, EntryMeta{}, store.loader(p.id, p.level)});
        ++counters.prefetch_requests;
      }
    }
  }

  void follow(const Vec3& position) {
    const ViewCellPartition& cells = pvs.partition();
    const std::optional<CellId> c = cells.locate(position);
    if (c && cells.cell(*c).skipped) fail_in_skipped_cell("vlod", cells.cell(*c), position);
    if (last_position) counters.crossings += boundaries_crossed(*last_position, position);
    last_position = position;
    const bool usable = c && !cells.cell(*c).solid;
    if (usable && c != cell) enter(*c, position, counters.frames);
    if (!usable) {
      cell.reset();
      pieces.clear();
    }
  }
};

VlodStrategy::VlodStrategy(const World& world, const VlodConfig& config, const StrategyOptions& options)
    : impl_(std::make_unique<Impl>(world, config, options)) {}

VlodStrategy::~VlodStrategy() = default;

std::string VlodStrategy::name() const {
  std::string settings;
  if (!impl_->config.cull) settings += "cull=0";
  if (!impl_->config.prefetch) settings += std::string(settings.empty() ? "" : ",") + "prefetch=0";
  return settings.empty() ? "vlod" : "vlod:" + settings;
}

// Outside every cell (or inside a solid one) no vLOD holds: the frame draws the frustum at
// level 0, as brute does, so the picture stays whole.
void VlodStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Stopwatch watch;
  Impl& s = *impl_;
  s.check_lens(camera);
  s.follow(camera.position);
  ++s.counters.frames;
  items.clear();
  const Frustum frustum(camera);
  auto add = [&](ObjectId id, uint32_t level) {
    const ObjectRecord& o = s.world.object(id);
    if (!s.config.cull || frustum.intersects(o.bounds)) items.push_back({id, level, o.color});
  };
  if (s.cell) {
    for (const Piece& p : s.pieces) add(p.id, p.level);
  } else {
    for (ObjectId id = 0; id < s.world.object_count(); ++id)
      if (frustum.intersects(s.world.object(id).bounds)) add(id, 0);
  }
  stats.query_ms += watch.ms();
}

// A level neither resident nor prefetched is read now: the frame stalls on it.
const Mesh* VlodStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  Impl& s = *impl_;
  s.current.reset();  // the renderer has uploaded it: let the store evict it
  const uint64_t misses = stats.cache_misses;
  s.current = s.store.get(item.id, item.lod, EntryMeta{}, stats);
  stats.stall = stats.stall || stats.cache_misses > misses;
  return s.current.get();
}

uint64_t VlodStrategy::resident_bytes() const { return impl_->store.resident_bytes(); }
uint64_t VlodStrategy::peak_resident_bytes() const { return impl_->store.peak_resident_bytes(); }
const VlodCounters& VlodStrategy::counters() const { return impl_->counters; }

}  // namespace cellwalk
