// The store's geometry cache: decoded levels of detail of a world's objects, read through the
// world file's verified pages and held in a BufferManager under the run's hard memory budget.
// The world's directory is reserved in the same budget for as long as the store lives.
#pragma once

#include <cstdint>
#include <memory>

#include "cellwalk/buffer_manager.hpp"
#include "cellwalk/frame_stats.hpp"
#include "cellwalk/world.hpp"

namespace cellwalk {

class GeometryStore {
 public:
  // budget_bytes 0 = unlimited. Throws Error if the world's directory alone exceeds it.
  // policy nullptr = LRU.
  GeometryStore(const World& world, uint64_t budget_bytes,
                std::unique_ptr<ReplacementPolicy> policy = nullptr);
  ~GeometryStore();

  // The decoded mesh of one level; reads and decodes on a miss, adding I/O and decode time,
  // bytes read, hits and misses to `stats`. A mesh too large for the budget even when
  // everything else is evicted is returned uncached and counted in resident_bytes() while the
  // caller holds it.
  std::shared_ptr<const Mesh> get(ObjectId id, uint32_t level, const EntryMeta& meta, FrameStats& stats);

  // Bytes held now: everything reserved in the budget plus uncached meshes still held.
  uint64_t resident_bytes() const;
  // The largest resident_bytes() seen at any get().
  uint64_t peak_resident_bytes() const { return peak_; }
  const MemoryBudget& budget() const { return budget_; }
  BufferManager& buffer() { return *buffer_; }
  const World& world() const { return world_; }

  static CacheKey key(ObjectId id, uint32_t level) { return (uint64_t(id) << 8) | level; }

 private:
  const World& world_;
  MemoryBudget budget_;
  uint64_t directory_bytes_ = 0;
  std::unique_ptr<BufferManager> buffer_;
  std::weak_ptr<const Mesh> transient_;  // the last uncached mesh handed out
  uint64_t transient_bytes_ = 0;
  uint64_t peak_ = 0;
};

}  // namespace cellwalk
