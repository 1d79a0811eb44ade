// Stratified thesis §3.2 (walkthrough mode), §5.1 (show styles), §5.2.2–§5.2.3 (ModelMgr and
// BoxMgr at run time); digest 002 §3.7. The cell is looked up by k-d descent; on a crossing
// its near list and far faces are read and decoded (the thesis's BoxMgr load). Without prefetch
// that happens in the frame that crosses, so its cost shows in that frame, as the thesis's
// spikes did; with it (the thesis's future work, §7: velocity-based prefetching) a thread loads
// the cells the viewer is heading for, and a crossing that finds its cell loaded costs nothing.
#include "cellwalk/systems/stratified/stratified_strategy.hpp"

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <iterator>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/systems/stratified/stored_stratified.hpp"
#include "core/stopwatch.hpp"
#include "strategy/strategy_config.hpp"

namespace cellwalk {

using namespace stratified;

namespace {

constexpr const char* kShowNames[] = {"full", "near", "far-objects", "far-texture", "brute"};

uint64_t bytes_of(const CellFarField& field) {
  uint64_t bytes = 0;
  for (const FaceImage& f : field.faces)
    bytes += f.color.rgba.capacity() + f.ids.ids.capacity() * sizeof(uint32_t) + f.depth.capacity() * sizeof(float);
  return bytes;
}

[[noreturn]] void fail_outside(const char* what, const Vec3& p) {
  char where[96];
  std::snprintf(where, sizeof where, "the camera at (%.1f, %.1f, %.1f)", p.x, p.y, p.z);
  fail("stratified", std::string(where) + what);
}

}  // namespace

bool is_stratified_strategy_name(const std::string& name) {
  return name == "stratified" || name.rfind("stratified:", 0) == 0;
}

StratifiedConfig parse_stratified_strategy_name(const std::string& name) {
  if (!is_stratified_strategy_name(name))
    fail("strategy \"" + name + "\"", "not a stratified name (stratified[:key=value,...])");
  StratifiedConfig c;
  for_each_strategy_setting(name, [&](const StrategySetting& s) {
    if (s.key == "show") {
      s.choice({"full", "near", "far-objects", "far-texture", "brute"});
      for (int i = 0; i < 5; ++i)
        if (s.value == kShowNames[i]) c.show = StratifiedConfig::Show(i);
    } else if (s.key == "cull") {
      c.cull = s.number(0, 1) != 0;
    } else if (s.key == "prefetch") {
      c.prefetch = s.number(0, 1) != 0;
    } else if (s.key == "lookahead") {
      c.lookahead_s = s.number(0, 60);
    } else if (s.key == "fade") {
      c.fade_frames = s.whole(0, 60);
    } else {
      s.unknown("show, cull, prefetch, lookahead, fade");
    }
  });
  return c;
}

namespace {

// A cell's run-time data: its near list and far field, and the bytes of the budget they hold.
struct CellData {
  std::vector<ObjectId> near;
  CellFarField field;
  uint64_t bytes = 0;
};

CellData load_cell(const StoredStratified& stored, CellId c, bool faces) {
  CellData d;
  d.near = stored.near(c);
  if (faces) d.field = stored.far_field(c);
  d.bytes = bytes_of(d.field) + d.near.capacity() * sizeof(ObjectId);
  return d;
}

// Loads cell c with its load bound reserved in `budget` for the load's duration (taken by
// `reserve`, which says whether it fits); the bytes the result holds stay reserved, the rest
// is released. nullopt when the bound does not fit. Rethrows what the load throws, released.
template <typename Reserve>
std::optional<CellData> load_within(const StoredStratified& stored, CellId c, bool faces, MemoryBudget& budget,
                                    Reserve reserve) {
  const uint64_t bound = stored.load_bound(c);
  if (!reserve(bound)) return std::nullopt;
  try {
    CellData d = load_cell(stored, c, faces);
    d.bytes = std::min(d.bytes, bound);
    budget.release(bound - d.bytes);
    return d;
  } catch (...) {
    budget.release(bound);
    throw;
  }
}

// Loads requested cells on a thread of its own, each charged to `budget` (try_reserve of its
// load bound before it is read: a cell that does not fit is dropped, never waited for). At most
// kSlots cells are queued, loading or ready.
// Thread-safety: every method may be called from the owning thread while the loader runs.
class CellLoader {
 public:
  static constexpr size_t kSlots = 3;

  CellLoader(const StoredStratified& stored, bool faces, MemoryBudget& budget)
      : stored_(stored), faces_(faces), budget_(budget), thread_([this] { run(); }) {}
  ~CellLoader() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
    for (auto& [cell, data] : ready_) budget_.release(data.bytes);
  }

  // Queues `c` unless it is queued, loading or ready, or every slot is taken.
  void request(CellId c) {
    std::lock_guard lock(mutex_);
    if (known(c) || queue_.size() + ready_.size() + (loading_ ? 1 : 0) >= kSlots) return;
    queue_.push_back(c);
    wake_.notify_all();
  }

  // `c`'s data if it is ready; if it is queued or loading, waits for it (and sets `waited`).
  // nullopt otherwise (or when it did not fit the budget). The bytes it holds pass to the caller.
  std::optional<CellData> take(CellId c, bool& waited) {
    std::unique_lock lock(mutex_);
    auto pending = [&] { return loading_ == c || std::find(queue_.begin(), queue_.end(), c) != queue_.end(); };
    waited = pending();
    done_.wait(lock, [&] { return !pending(); });
    const auto it = ready_.find(c);
    if (it == ready_.end()) return std::nullopt;
    CellData d = std::move(it->second);
    ready_.erase(it);
    return d;
  }

  // Drops queued and ready cells that are not in `wanted` (the viewer turned away).
  void keep_only(const std::vector<CellId>& wanted) {
    std::lock_guard lock(mutex_);
    auto unwanted = [&](CellId c) { return std::find(wanted.begin(), wanted.end(), c) == wanted.end(); };
    std::erase_if(queue_, unwanted);
    for (auto it = ready_.begin(); it != ready_.end();) {
      if (!unwanted(it->first)) {
        ++it;
        continue;
      }
      budget_.release(it->second.bytes);
      it = ready_.erase(it);
    }
  }

  uint64_t loaded() const {
    std::lock_guard lock(mutex_);
    return loaded_;
  }
  // Bytes of far-field records the loader has read.
  uint64_t read_bytes() const {
    std::lock_guard lock(mutex_);
    return read_bytes_;
  }

 private:
  // REQUIRES: mutex_ held.
  bool known(CellId c) const {
    return loading_ == c || ready_.count(c) || std::find(queue_.begin(), queue_.end(), c) != queue_.end();
  }

  void run() {
    std::unique_lock lock(mutex_);
    while (true) {
      wake_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      const CellId c = queue_.front();
      queue_.pop_front();
      loading_ = c;
      lock.unlock();
      std::optional<CellData> d;
      try {
        d = load_within(stored_, c, faces_, budget_, [&](uint64_t bytes) { return budget_.try_reserve(bytes); });
      } catch (const std::exception&) {
        d.reset();  // the crossing loads it itself and reports the damage
      }
      lock.lock();
      loading_.reset();
      if (d) {
        read_bytes_ += faces_ ? stored_.far_field_bytes(c) : 0;
        ready_.emplace(c, std::move(*d));
        ++loaded_;
      }
      done_.notify_all();
    }
  }

  const StoredStratified& stored_;
  bool faces_;
  MemoryBudget& budget_;
  mutable std::mutex mutex_;
  std::condition_variable wake_, done_;
  std::deque<CellId> queue_;
  std::optional<CellId> loading_;
  std::map<CellId, CellData> ready_;
  uint64_t loaded_ = 0, read_bytes_ = 0;
  bool stop_ = false;
  std::thread thread_;  // last: started once everything it uses exists
};

}  // namespace

struct StratifiedStrategy::Impl {
  Impl(const World& w, const StratifiedConfig& c, const StrategyOptions& o)
      : world(w), config(c), stored(w), store(w, o.memory_budget_bytes, nullptr, 1, open_level_source(w, o.objects_db)) {
    index_bytes = stored.resident_bytes();
    if (!store.buffer().budget().try_reserve(index_bytes))
      fail("stratified", "the memory budget cannot hold the stored cells and near lists (" + std::to_string(index_bytes) +
                             " bytes) beside the geometry store; raise --budget");
    if (config.prefetch) loader = std::make_unique<CellLoader>(stored, uses_faces(), store.buffer().budget());
  }
  ~Impl() {
    loader.reset();
    store.buffer().budget().release(index_bytes + cell.bytes + previous.bytes);
  }

  bool uses_faces() const {
    return config.show == StratifiedConfig::Show::kFull || config.show == StratifiedConfig::Show::kFarTexture;
  }

  // Makes `c` the current cell: the fading cell when the viewer turned back into it, its data
  // from the loader, or loaded here (a stall after the first frame). With a fade, the cell left
  // becomes the fading one, still charged; otherwise its bytes are released. Returns the
  // milliseconds it took in this frame.
  double enter(CellId c, FrameStats& stats) {
    Stopwatch watch;
    std::optional<CellData> back;  // the fading cell, entered again: nothing to load
    if (previous_cell == c) {
      back = std::move(previous);
      previous = {};
      previous_cell.reset();
    }
    drop_previous();
    if (config.fade_frames > 0 && current && !cell.field.faces.empty()) {
      previous = std::move(cell);
      previous_cell = current;
      fade_step = 0;
    } else {
      store.buffer().budget().release(cell.bytes);
    }
    cell = {};
    const bool first = !current.has_value();
    if (back)
      cell = std::move(*back);
    else
      load(c, first, stats);
    current = c;
    counters.crossings += first ? 0 : 1;
    const double ms = watch.ms();
    counters.load_ms += ms;
    stats.io_ms += ms;
    peak = std::max(peak, store.resident_bytes());
    return ms;
  }

  // Makes cell `c`'s data the current one, from the loader or read here; counts a stall when a
  // frame after the first had to load it or wait for it.
  void load(CellId c, bool first, FrameStats& stats) {
    bool waited = false;
    std::optional<CellData> ready = loader ? loader->take(c, waited) : std::nullopt;
    const bool from_loader = ready.has_value();
    if (ready) {
      cell = std::move(*ready);
      if (!waited) ++counters.prefetch_hits;
    } else {
      MemoryBudget& budget = store.buffer().budget();
      auto reserve = [&](uint64_t bytes) { return store.buffer().reserve(bytes); };
      ready = load_within(stored, c, uses_faces(), budget, reserve);
      if (!ready && previous_cell) {  // the fade is a nicety: give its bytes to the load
        drop_previous();
        ready = load_within(stored, c, uses_faces(), budget, reserve);
      }
      if (!ready)
        fail("stratified", "the memory budget cannot hold loading cell " + std::to_string(c) + "'s near list and far faces (" +
                               std::to_string(stored.load_bound(c)) + " bytes) beside the cells; raise --budget");
      cell = std::move(*ready);
      const uint64_t record = uses_faces() ? stored.far_field_bytes(c) : 0;
      stats.bytes_read += record;
      read_in_frames += record;
      counters.loaded_bytes += record;
    }
    if (!first && (!from_loader || waited)) {  // the frame loaded its cell or waited for it
      ++counters.stalls;
      stats.stall = true;
    }
  }

  // Releases the fading cell's bytes and forgets it.
  void drop_previous() {
    store.buffer().budget().release(previous.bytes);
    previous = {};
    previous_cell.reset();
  }

  // A frame without a crossing moves the fade on; it ends after fade_frames frames.
  void advance_fade() {
    if (previous_cell && ++fade_step >= config.fade_frames) drop_previous();
  }

  void append_faces(const CellData& data, CellId c, float opacity) {
    const Vec3 centre = stored.partition().cell(c).box.center();
    for (const FaceImage& f : data.field.faces) {
      FarFace quad = face_quad(centre, stored.params().b, f.face, c * kFaceCount + uint32_t(f.face));
      quad.color = &f.color;
      quad.ids = &f.ids;
      quad.opacity = opacity;
      faces.push_back(quad);
    }
  }

  // The current cell's faces, then the fading cell's over them: k frames after the crossing
  // (k = 0 at the crossing) at opacity 1 − (k + 1)/(fade_frames + 1).
  void make_faces() {
    faces.clear();
    append_faces(cell, *current, 1.0f);
    if (!previous_cell) return;
    append_faces(previous, *previous_cell, 1.0f - float(fade_step + 1) / float(config.fade_frames + 1));
    ++counters.faded_frames;
  }

  // Asks the loader for the cells the viewer reaches within the lookahead at its present
  // velocity (from the last frame's position and path time).
  void prefetch(const Camera& camera, double time) {
    if (!loader) return;
    std::vector<CellId> wanted;
    if (last_time && time > *last_time) {
      const Vec3 velocity = (camera.position - last_position) / float(time - *last_time);
      for (int k = 1; k <= 6; ++k) {
        const std::optional<CellId> c =
            stored.partition().locate(camera.position + velocity * float(config.lookahead_s * k / 6.0));
        if (c && c != current && c != previous_cell && stored.partition().cell(*c).computed() &&
            std::find(wanted.begin(), wanted.end(), *c) == wanted.end())
          wanted.push_back(*c);
      }
    }
    loader->keep_only(wanted);
    for (const CellId c : wanted) loader->request(c);
    last_position = camera.position;
    last_time = time;
    counters.prefetched = loader->loaded();
    counters.loaded_bytes = read_in_frames + loader->read_bytes();
  }

  // Whether object `id` is drawn as polygons in this show style.
  bool drawn_as_polygon(ObjectId id, size_t& next_near) const {
    const std::vector<ObjectId>& near = cell.near;
    while (next_near < near.size() && near[next_near] < id) ++next_near;
    const bool is_near = next_near < near.size() && near[next_near] == id;
    switch (config.show) {
      case StratifiedConfig::Show::kFull:
      case StratifiedConfig::Show::kNear: return is_near;
      case StratifiedConfig::Show::kFarObjects: return !is_near;
      case StratifiedConfig::Show::kFarTexture: return false;
      case StratifiedConfig::Show::kBrute: return true;
    }
    return false;
  }

  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
    Stopwatch watch;
    items.clear();
    const std::optional<CellId> c = stored.partition().locate(camera.position);
    if (!c) fail_outside(" is outside the stratified viewcells; walk inside the world the cells were built for", camera.position);
    if (!stored.partition().cell(*c).computed())
      fail_outside((" is in viewcell " + std::to_string(*c) +
                    ", which `cellwalk stratify build --along` left unbaked; rebuild with the path it walks or without --along").c_str(),
                   camera.position);
    crossed = !current || *current != *c;
    if (!crossed) advance_fade();
    const double load_ms = crossed ? enter(*c, stats) : 0.0;
    make_faces();
    prefetch(camera, stats.time);
    ++counters.frames;
    counters.near_objects += cell.near.size();
    const Frustum frustum(camera);
    size_t next_near = 0;
    const bool all = config.show == StratifiedConfig::Show::kBrute || config.show == StratifiedConfig::Show::kFarObjects;
    if (all) {
      for (ObjectId id = 0; id < world.object_count(); ++id)
        if (drawn_as_polygon(id, next_near) && (!config.cull || frustum.intersects(world.object(id).bounds)))
          items.push_back({id, 0, world.object(id).color});
    } else if (config.show != StratifiedConfig::Show::kFarTexture) {
      // While the cell left fades, its near objects stay polygons: its faces do not show them,
      // so they would fade out with them.
      if (previous_cell) {
        near_union.clear();
        std::set_union(cell.near.begin(), cell.near.end(), previous.near.begin(), previous.near.end(),
                       std::back_inserter(near_union));
      }
      for (const ObjectId id : previous_cell ? near_union : cell.near)
        if (!config.cull || frustum.intersects(world.object(id).bounds)) items.push_back({id, 0, world.object(id).color});
    }
    stats.query_ms += watch.ms() - load_ms;
  }

  const World& world;
  StratifiedConfig config;
  StoredStratified stored;
  GeometryStore store;
  uint64_t index_bytes = 0;
  uint64_t read_in_frames = 0;  // far-field record bytes the frames read themselves
  uint64_t peak = 0;  // resident bytes after each load (the store's own peak is taken at its gets)
  std::optional<CellId> current;
  bool crossed = false;
  CellData cell;  // the current cell's
  CellData previous;  // the cell left at the last crossing, while its faces fade out
  std::optional<CellId> previous_cell;
  int fade_step = 0;  // frames since that crossing
  std::vector<ObjectId> near_union;  // the two cells' near lists while one fades
  std::vector<FarFace> faces;
  std::shared_ptr<const Mesh> mesh;  // handed to the renderer for upload
  StratifiedCounters counters;
  Vec3 last_position{0.0f};
  std::optional<double> last_time;
  std::unique_ptr<CellLoader> loader;  // last: destroyed first, while what it uses still exists
};

StratifiedStrategy::StratifiedStrategy(const World& world, const StratifiedConfig& config, const StrategyOptions& options)
    : impl_(std::make_unique<Impl>(world, config, options)) {}

StratifiedStrategy::~StratifiedStrategy() = default;

std::string StratifiedStrategy::name() const {
  std::string name = "stratified";
  if (impl_->config.show != StratifiedConfig::Show::kFull) name += std::string(":show=") + kShowNames[int(impl_->config.show)];
  auto add = [&](const std::string& setting) { name += (name.find(':') == std::string::npos ? ":" : ",") + setting; };
  if (!impl_->config.cull) add("cull=0");
  if (!impl_->config.prefetch) add("prefetch=0");
  if (impl_->config.fade_frames > 0) add("fade=" + std::to_string(impl_->config.fade_frames));
  return name;
}

void StratifiedStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  impl_->select(camera, items, stats);
}

const Mesh* StratifiedStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  impl_->mesh.reset();  // the renderer has uploaded it: let the store evict it
  impl_->mesh = impl_->store.get(item.id, item.lod, EntryMeta{}, stats);
  return impl_->mesh.get();
}

std::span<const FarFace> StratifiedStrategy::far_faces() const { return impl_->faces; }

double StratifiedStrategy::far_angle(const Camera& camera) const {
  if (!impl_->current) return 0.0;
  // A fading cell is seen from outside it: its faces count too, however faint.
  const auto angle = [&](const CellData& data, CellId c) {
    return far_field_angle(data.field, impl_->stored.partition().cell(c).box.center(), impl_->stored.params().b, camera);
  };
  const double now = angle(impl_->cell, *impl_->current);
  return impl_->previous_cell ? std::max(now, angle(impl_->previous, *impl_->previous_cell)) : now;
}

bool StratifiedStrategy::crossed() const { return impl_->crossed; }

void StratifiedStrategy::overlay(std::vector<LineSegment>& lines) const {
  if (!impl_->current) return;
  const ViewCell& cell = impl_->stored.partition().cell(*impl_->current);
  append_box_lines(cell.box, rgba8(0, 255, 255), lines);
  append_box_lines(bounding_box(cell, impl_->stored.params().b), rgba8(255, 255, 255), lines);
}

uint64_t StratifiedStrategy::resident_bytes() const { return impl_->store.resident_bytes(); }

uint64_t StratifiedStrategy::peak_resident_bytes() const {
  return std::max(impl_->peak, impl_->store.peak_resident_bytes());
}

const StratifiedCounters& StratifiedStrategy::counters() const { return impl_->counters; }

}  // namespace cellwalk
