// vLOD's run time (seed 001 §2, §6; digest 001 §3.8): locate the viewer's cell; at each cell
// change apply the Δ from the old vLOD to the new (drop R, load A); prefetch what the face
// neighbours add, asynchronously; draw the vLOD. Nothing is traversed per frame but the vLOD
// itself (optionally frustum-culled, a choice the seed leaves open).
#include "cellwalk/systems/vlod/vlod_strategy.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <optional>

#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/lod/screen_error.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/store/prefetcher.hpp"
#include "cellwalk/visibility/cell_lod.hpp"
#include "cellwalk/visibility/stored_vlod.hpp"
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

using visibility::PieceId;

// The most face steps searched for a chain of Δs between two cells before the move is taken as
// a teleport (rebuilt from the nearest key cell).
constexpr int kMaxChain = 16;

void apply(std::vector<PieceId>& vlod, const visibility::VlodDelta& d) {
  std::vector<PieceId> kept, out;
  std::set_difference(vlod.begin(), vlod.end(), d.removed.begin(), d.removed.end(), std::back_inserter(kept));
  std::set_union(kept.begin(), kept.end(), d.added.begin(), d.added.end(), std::back_inserter(out));
  vlod.swap(out);
}

uint64_t bytes_of(const visibility::VlodDelta& d) { return (d.added.capacity() + d.removed.capacity()) * sizeof(PieceId); }

}  // namespace

struct VlodStrategy::Impl {
  Impl(const World& w, const VlodConfig& c, const StrategyOptions& o)
      : world(w),
        config(c),
        options(o),
        vlod(w),
        store(w, o.memory_budget_bytes, nullptr, c.prefetch ? 2 : 1, open_level_source(w, o.objects_db)),
        prefetcher(store.buffer(), PrefetcherOptions{c.prefetch ? 1u : 0u, 1}) {
    index_bytes = vlod.resident_bytes();
    if (!store.buffer().budget().try_reserve(index_bytes))
      fail(w.file().path(), "memory budget of " + byte_size_text(o.memory_budget_bytes) +
                                " cannot hold the vLOD index (" + byte_size_text(index_bytes) +
                                ") beside the directory and the loads in flight; give a larger --budget");
  }
  ~Impl() {
    drop_face_deltas();
    store.buffer().budget().release(index_bytes + pieces_bytes);
  }

  const World& world;
  VlodConfig config;
  StrategyOptions options;
  visibility::StoredVlod vlod;
  GeometryStore store;
  uint64_t index_bytes = 0;
  std::optional<CellId> cell;       // the cell whose vLOD `pieces` is; none outside every cell
  std::vector<PieceId> pieces;      // ascending
  uint64_t pieces_bytes = 0;        // charged for `pieces`
  // §6: the Δs of the current cell's faces, read on entering it, charged to the budget.
  std::vector<std::pair<CellId, visibility::VlodDelta>> face_deltas;
  uint64_t face_bytes = 0;
  VlodCounters counters;
  std::shared_ptr<const Mesh> current;  // the mesh handed to the renderer for upload
  Prefetcher prefetcher;                // last: destroyed first, while what its jobs use exists

  void check_lens(const Camera& camera) const {
    const visibility::CellLodRule& rule = vlod.rule();
    const float height = options.viewport_height_px > 0 ? options.viewport_height_px : rule.lens.viewport_height_px;
    if (!visibility::rule_covers(rule, lens_of(camera, height)))
      fail("vlod", "the levels were chosen for " + visibility::to_string(rule) + ", and an image " +
                       std::to_string(int(height)) + " px high at fov " + std::to_string(int(camera.fov_y_deg)) +
                       "° would magnify their error past that bound; render smaller, or rerun "
                       "`cellwalk pvs --engine vlod` with a larger --lod-height or --lod-fov");
  }

  // Charges `bytes` more (or fewer) to the hard budget, evicting cached geometry if it must.
  void recharge(uint64_t& held, uint64_t bytes) {
    store.buffer().budget().release(held);
    held = 0;
    if (!store.buffer().reserve(bytes))
      fail("vlod", "memory budget of " + byte_size_text(options.memory_budget_bytes) + " cannot hold the vLOD of cell " +
                       std::to_string(cell ? *cell : 0) + " (" + byte_size_text(bytes) + "); give a larger --budget");
    held = bytes;
  }

  void drop_face_deltas() {
    face_deltas.clear();
    store.buffer().budget().release(face_bytes);
    face_bytes = 0;
  }

  // The Δ from the current cell to `next`: the prefetched one, else read now.
  std::optional<visibility::VlodDelta> delta_to(CellId from, CellId next) {
    if (cell && from == *cell)
      for (auto& [n, d] : face_deltas)
        if (n == next) return std::move(d);
    return vlod.delta(from, next);
  }

  // Face steps from `from` to `to` over cells with vLODs (BFS, at most kMaxChain); empty if none.
  std::vector<CellId> chain(CellId from, const std::function<bool(CellId)>& is_goal) const {
    std::vector<int> parent(vlod.partition().cell_count(), -1);
    std::vector<CellId> frontier{from};
    parent[from] = int(from);
    for (int step = 0; step <= kMaxChain && !frontier.empty(); ++step) {
      std::vector<CellId> next;
      for (CellId c : frontier) {
        if (is_goal(c)) {
          std::vector<CellId> path{c};
          while (path.back() != from) path.push_back(CellId(parent[path.back()]));
          return path;  // goal first, `from` last
        }
        for (CellId n : vlod.neighbours(c))
          if (parent[n] < 0) parent[n] = int(c), next.push_back(n);
      }
      frontier.swap(next);
    }
    return {};
  }

  // §2.3 / digest §3.8: from the current cell through each intermediate cell to `target`, one
  // Δ per face crossed; a move with no chain of Δs (a teleport, the start) is rebuilt from the
  // nearest key cell.
  void move_to(CellId target) {
    std::vector<CellId> steps;
    if (cell) {
      steps = chain(target, [&](CellId c) { return c == *cell; });  // the current cell first
    }
    if (steps.empty()) {
      steps = chain(target, [&](CellId c) { return vlod.is_key(c); });
      if (steps.empty()) fail("vlod", "cell " + std::to_string(target) + " has no key cell within " + std::to_string(kMaxChain) + " face steps (the vlod section is damaged)");
      pieces = vlod.key_vlod(steps.front());
      cell = steps.front();
      drop_face_deltas();
    }
    for (size_t i = 1; i < steps.size(); ++i) {
      const std::optional<visibility::VlodDelta> d = delta_to(steps[i - 1], steps[i]);
      if (!d) fail("vlod", "no Δ from cell " + std::to_string(steps[i - 1]) + " to " + std::to_string(steps[i]) + " (the vlod section is damaged)");
      for (PieceId p : d->removed)
        store.buffer().erase(GeometryStore::key(vlod.pieces().object(p), vlod.pieces().level(p)));
      apply(pieces, *d);
      ++counters.crossings;
      counters.added += d->added.size();
      counters.removed += d->removed.size();
      cell = steps[i];
      drop_face_deltas();
    }
  }

  // §6: read the Δs of the new cell's faces and prefetch the geometry they add, nearest first.
  void prefetch_faces(const Vec3& position, uint64_t frame) {
    prefetcher.cancel_older_than(frame);
    uint64_t bytes = 0;
    for (CellId n : vlod.neighbours(*cell)) {
      std::optional<visibility::VlodDelta> d = vlod.delta(*cell, n);
      if (!d) continue;
      const double priority = -double(distance_to_box(position, vlod.partition().cell(n).box));
      for (PieceId p : d->added) {
        const ObjectId id = vlod.pieces().object(p);
        const uint32_t level = vlod.pieces().level(p);
        prefetcher.submit({GeometryStore::key(id, level), priority, frame, EntryMeta{}, store.loader(id, level)});
        ++counters.prefetch_requests;
      }
      bytes += bytes_of(*d);
      face_deltas.emplace_back(n, std::move(*d));
    }
    recharge(face_bytes, bytes);
  }

  void follow(const Vec3& position) {
    const ViewCellPartition& cells = vlod.partition();
    const std::optional<CellId> c = cells.locate(position);
    if (c && cells.cell(*c).skipped) fail_in_skipped_cell("vlod", cells.cell(*c), position);
    const bool usable = c && vlod.has_vlod(*c);
    if (usable && c != cell) {
      const uint64_t changed = counters.added + counters.removed;
      move_to(*c);
      ++counters.cell_changes;
      counters.delta_fractions.push_back(pieces.empty() ? 0.0 : double(counters.added + counters.removed - changed) / double(pieces.size()));
      recharge(pieces_bytes, pieces.capacity() * sizeof(PieceId));
      if (config.prefetch) prefetch_faces(position, counters.frames);
      counters.section_bytes_read = vlod.bytes_read();
    }
    if (!usable) {
      cell.reset();
      pieces.clear();
      drop_face_deltas();
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
    for (PieceId p : s.pieces) add(s.vlod.pieces().object(p), s.vlod.pieces().level(p));
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
