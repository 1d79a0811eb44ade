// Stratified thesis §3.2 (walkthrough mode), §5.1 (show styles), §5.2.2–§5.2.3 (ModelMgr and
// BoxMgr at run time); digest 002 §3.7. The cell is looked up by k-d descent; on a crossing
// its near list and far faces are read and decoded (the thesis's BoxMgr load; done in the frame
// that crosses, so its cost shows in that frame's I/O time, as the thesis's spikes did).
#include "cellwalk/systems/stratified/stratified_strategy.hpp"

#include <algorithm>
#include <cstdio>
#include <optional>

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
    } else {
      s.unknown("show, cull");
    }
  });
  return c;
}

struct StratifiedStrategy::Impl {
  Impl(const World& w, const StratifiedConfig& c, const StrategyOptions& o)
      : world(w), config(c), stored(w), store(w, o.memory_budget_bytes) {
    index_bytes = stored.resident_bytes();
    if (!store.buffer().budget().try_reserve(index_bytes))
      fail("stratified", "the memory budget cannot hold the stored cells and near lists (" + std::to_string(index_bytes) +
                             " bytes) beside the geometry store; raise --budget");
  }
  ~Impl() { store.buffer().budget().release(index_bytes + field_bytes); }

  bool uses_faces() const {
    return config.show == StratifiedConfig::Show::kFull || config.show == StratifiedConfig::Show::kFarTexture;
  }

  // Loads cell `c`'s near list and, when they are drawn, its far faces, charging the decoded
  // faces to the budget (the previous cell's are released first).
  // Returns the milliseconds the load took.
  double enter(CellId c, FrameStats& stats) {
    Stopwatch watch;
    near = stored.near(c);
    faces.clear();
    field = {};
    store.buffer().budget().release(field_bytes);
    field_bytes = 0;
    if (uses_faces()) {
      const uint64_t record = stored.far_field_bytes(c);
      field = stored.far_field(c);
      field_bytes = bytes_of(field);
      if (!store.buffer().reserve(field_bytes))
        fail("stratified", "the memory budget cannot hold cell " + std::to_string(c) + "'s far faces (" +
                               std::to_string(field_bytes) + " bytes) beside the cells; raise --budget");
      stats.bytes_read += record;
      counters.loaded_bytes += record;
      const Vec3 centre = stored.partition().cell(c).box.center();
      for (const FaceImage& f : field.faces) {
        FarFace quad = face_quad(centre, stored.params().b, f.face, c * kFaceCount + uint32_t(f.face));
        quad.color = &f.color;
        quad.ids = &f.ids;
        faces.push_back(quad);
      }
    }
    current = c;
    ++counters.crossings;
    const double ms = watch.ms();
    counters.load_ms += ms;
    stats.io_ms += ms;
    peak = std::max(peak, store.resident_bytes());
    return ms;
  }

  // Whether object `id` is drawn as polygons in this show style.
  bool drawn_as_polygon(ObjectId id, size_t& next_near) const {
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
    const double load_ms = crossed ? enter(*c, stats) : 0.0;
    ++counters.frames;
    counters.near_objects += near.size();
    const Frustum frustum(camera);
    size_t next_near = 0;
    const bool all = config.show == StratifiedConfig::Show::kBrute || config.show == StratifiedConfig::Show::kFarObjects;
    if (all) {
      for (ObjectId id = 0; id < world.object_count(); ++id)
        if (drawn_as_polygon(id, next_near) && (!config.cull || frustum.intersects(world.object(id).bounds)))
          items.push_back({id, 0, world.object(id).color});
    } else if (config.show != StratifiedConfig::Show::kFarTexture) {
      for (const ObjectId id : near)
        if (!config.cull || frustum.intersects(world.object(id).bounds)) items.push_back({id, 0, world.object(id).color});
    }
    stats.query_ms += watch.ms() - load_ms;
  }

  const World& world;
  StratifiedConfig config;
  StoredStratified stored;
  GeometryStore store;
  uint64_t index_bytes = 0, field_bytes = 0;
  uint64_t peak = 0;  // resident bytes after each load (the store's own peak is taken at its gets)
  std::optional<CellId> current;
  bool crossed = false;
  std::vector<ObjectId> near;
  CellFarField field;
  std::vector<FarFace> faces;
  std::shared_ptr<const Mesh> mesh;  // handed to the renderer for upload
  StratifiedCounters counters;
};

StratifiedStrategy::StratifiedStrategy(const World& world, const StratifiedConfig& config, const StrategyOptions& options)
    : impl_(std::make_unique<Impl>(world, config, options)) {}

StratifiedStrategy::~StratifiedStrategy() = default;

std::string StratifiedStrategy::name() const {
  std::string name = "stratified";
  if (impl_->config.show != StratifiedConfig::Show::kFull) name += std::string(":show=") + kShowNames[int(impl_->config.show)];
  if (!impl_->config.cull) name += name.find(':') == std::string::npos ? ":cull=0" : ",cull=0";
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
  const Vec3 centre = impl_->stored.partition().cell(*impl_->current).box.center();
  return far_field_angle(impl_->field, centre, impl_->stored.params().b, camera);
}

bool StratifiedStrategy::crossed() const { return impl_->crossed; }

uint64_t StratifiedStrategy::resident_bytes() const { return impl_->store.resident_bytes(); }

uint64_t StratifiedStrategy::peak_resident_bytes() const {
  return std::max(impl_->peak, impl_->store.peak_resident_bytes());
}

const StratifiedCounters& StratifiedStrategy::counters() const { return impl_->counters; }

}  // namespace cellwalk
