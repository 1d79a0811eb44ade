#include "cellwalk/store/geometry_store.hpp"

#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/error.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk {
namespace {

// An upper bound of a decoded level's bytes: levels are stored compacted (every vertex used),
// so at most 3 vertices per triangle, each with a position, a normal and a colour.
uint64_t decoded_bound(uint64_t triangles) {
  return sizeof(Mesh) + triangles * (3 * (sizeof(Vec3) * 2 + sizeof(Rgba8)) + 3 * sizeof(uint32_t));
}

// What one load holds outside the cache at most: the encoded level and its decoded mesh.
uint64_t largest_load(const World& world) {
  uint64_t largest = 0;
  for (ObjectId id = 0; id < world.object_count(); ++id)
    for (uint32_t level = 0; level < world.object(id).lod_count; ++level) {
      const LodRecord& l = world.lod(id, level);
      largest = std::max(largest, l.bytes + decoded_bound(l.triangles));
    }
  return largest;
}

}  // namespace

// The cache's own limit leaves room for one load in flight, so what is cached plus what is
// being read and decoded never passes the caller's budget.
GeometryStore::GeometryStore(const World& world, uint64_t budget_bytes, std::unique_ptr<ReplacementPolicy> policy,
                             unsigned loads_in_flight, std::unique_ptr<LevelSource> source)
    : world_(world),
      source_(source ? std::move(source) : world_level_source(world)),
      load_headroom_(largest_load(world) * std::max(1u, loads_in_flight)),
      budget_(budget_bytes == 0 ? 0 : budget_bytes > load_headroom_ ? budget_bytes - load_headroom_ : 1),
      directory_bytes_(world.resident_bytes() + source_->resident_bound()) {
  const uint64_t fixed = fixed_bytes(world, loads_in_flight, source_->resident_bound());
  if (budget_bytes != 0 && budget_bytes < fixed)
    fail(world.file().path(), "memory budget of " + byte_size_text(budget_bytes) + " is too small: the world's directory" +
                                  (source_->resident_bound() ? ", the object database's cache" : "") +
                                  " and its largest level need " + byte_size_text(fixed) + "; give a larger --budget");
  if (!budget_.try_reserve(directory_bytes_)) fail(world.file().path(), "internal: directory does not fit the budget");
  buffer_ = std::make_unique<BufferManager>(budget_, policy ? std::move(policy) : make_lru_policy());
  peak_ = resident_bytes();
}

uint64_t GeometryStore::fixed_bytes(const World& world, unsigned loads_in_flight, uint64_t source_bytes) {
  return world.resident_bytes() + source_bytes + largest_load(world) * std::max(1u, loads_in_flight);
}

GeometryStore::~GeometryStore() {
  buffer_.reset();  // releases every cached item's reservation first
  budget_.release(directory_bytes_);
}

void GeometryStore::raise_peak(uint64_t bytes) {
  for (uint64_t seen = peak_.load(); bytes > seen && !peak_.compare_exchange_weak(seen, bytes);) {
  }
}

// The peak counts the load's encoded and decoded bytes beside what the budget holds; with
// loads on two threads each counts itself, and the budget keeps room for both.
LoadedItem GeometryStore::load(ObjectId id, uint32_t level, FetchStats& stats) {
  Stopwatch watch;
  auto bytes = source_->read_level(id, level);
  stats.io_ms += watch.lap_ms();
  stats.bytes_read += bytes.size();
  auto mesh = std::make_shared<const Mesh>(world_.decode_level(id, level, bytes));
  stats.decode_ms += watch.lap_ms();
  const uint64_t mesh_bytes = sizeof(Mesh) + mesh->byte_size();
  if (mesh_bytes > decoded_bound(mesh->triangle_count()))
    fail(source_->path() + ": object " + std::to_string(id) + " level " + std::to_string(level),
         "decodes to unreferenced vertices (the file is damaged)");
  raise_peak(budget_.used() + bytes.size() + mesh_bytes);
  return {mesh, mesh_bytes};
}

ItemLoader GeometryStore::loader(ObjectId id, uint32_t level) {
  return [this, id, level]() -> LoadedItem {
    FetchStats stats;
    LoadedItem item = load(id, level, stats);
    std::lock_guard lock(prefetched_mutex_);
    prefetched_.io_ms += stats.io_ms;
    prefetched_.decode_ms += stats.decode_ms;
    prefetched_.bytes_read += stats.bytes_read;
    return item;
  };
}

FetchStats GeometryStore::prefetched() const {
  std::lock_guard lock(prefetched_mutex_);
  return prefetched_;
}

std::shared_ptr<const Mesh> GeometryStore::get(ObjectId id, uint32_t level, const EntryMeta& meta, FetchStats& stats) {
  ItemLoader loader = [&]() -> LoadedItem { return load(id, level, stats); };
  CacheResult r = buffer_->get(key(id, level), meta, loader);
  (r.hit ? stats.cache_hits : stats.cache_misses) += 1;
  auto mesh = BufferManager::get_as<Mesh>(r);
  if (!r.cached) {
    transient_ = mesh;
    transient_bytes_ = sizeof(Mesh) + mesh->byte_size();
  }
  raise_peak(resident_bytes());
  return mesh;
}

uint64_t GeometryStore::resident_bytes() const {
  return budget_.used() + (transient_.expired() ? 0 : transient_bytes_);
}

}  // namespace cellwalk
