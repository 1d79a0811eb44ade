#include "cellwalk/geometry_store.hpp"

#include "cellwalk/error.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk {

GeometryStore::GeometryStore(const World& world, uint64_t budget_bytes, std::unique_ptr<ReplacementPolicy> policy)
    : world_(world), budget_(budget_bytes), directory_bytes_(world.resident_bytes()) {
  if (!budget_.try_reserve(directory_bytes_))
    fail(world.file().path(), "memory budget of " + std::to_string(budget_bytes) + " bytes is smaller than the world's directory (" +
                                  std::to_string(directory_bytes_) + " bytes): give a larger --budget");
  buffer_ = std::make_unique<BufferManager>(budget_, policy ? std::move(policy) : make_lru_policy());
  peak_ = resident_bytes();
}

GeometryStore::~GeometryStore() {
  buffer_.reset();  // releases every cached item's reservation first
  budget_.release(directory_bytes_);
}

std::shared_ptr<const Mesh> GeometryStore::get(ObjectId id, uint32_t level, const EntryMeta& meta, FrameStats& stats) {
  ItemLoader loader = [&]() -> LoadedItem {
    Stopwatch watch;
    auto bytes = world_.read_level(id, level);
    stats.io_ms += watch.lap_ms();
    stats.bytes_read += bytes.size();
    auto mesh = std::make_shared<const Mesh>(world_.decode_level(id, level, bytes));
    stats.decode_ms += watch.lap_ms();
    return {mesh, sizeof(Mesh) + mesh->byte_size()};
  };
  CacheResult r = buffer_->get(key(id, level), meta, loader);
  (r.hit ? stats.cache_hits : stats.cache_misses) += 1;
  auto mesh = BufferManager::get_as<Mesh>(r);
  if (!r.cached) {
    transient_ = mesh;
    transient_bytes_ = sizeof(Mesh) + mesh->byte_size();
  }
  peak_ = std::max(peak_, resident_bytes());
  return mesh;
}

uint64_t GeometryStore::resident_bytes() const {
  return budget_.used() + (transient_.expired() ? 0 : transient_bytes_);
}

}  // namespace cellwalk
