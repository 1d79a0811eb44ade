// The store's geometry cache: decoded levels of detail of a world's objects, read from a
// LevelSource (the world file's verified pages, or an object database built from the world) and
// held in a BufferManager under the run's hard memory budget. The world's directory and what the
// source holds are reserved in the same budget for as long as the store lives.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>

#include "cellwalk/store/buffer_manager.hpp"
#include "cellwalk/store/fetch_stats.hpp"
#include "cellwalk/store/level_source.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

class GeometryStore {
 public:
  // budget_bytes 0 = unlimited; otherwise the directory, the source's resident_bound(), the
  // cached meshes and the one level being read and decoded stay within it together. Throws Error
  // if the budget cannot hold the directory, the source's bound plus the world's largest level.
  // policy nullptr = LRU. loads_in_flight: how many levels may be read and decoded at once
  // (the budget keeps room for each): 1 for get() alone, 2 with a prefetching thread.
  // source nullptr = the world file (open_level_source(world, options.objects_db) in a strategy).
  GeometryStore(const World& world, uint64_t budget_bytes,
                std::unique_ptr<ReplacementPolicy> policy = nullptr, unsigned loads_in_flight = 1,
                std::unique_ptr<LevelSource> source = nullptr);
  ~GeometryStore();

  // What a store over `world` holds whatever it caches: the directory, room for
  // `loads_in_flight` of the world's largest level, encoded and decoded, and its source's bound
  // (level_source_bound; 0 for the world file). A budget must exceed it.
  static uint64_t fixed_bytes(const World& world, unsigned loads_in_flight, uint64_t source_bytes = 0);

  // The decoded mesh of one level; reads and decodes on a miss, adding I/O and decode time,
  // bytes read, hits and misses to `stats`. A mesh too large for the budget even when
  // everything else is evicted is returned uncached and counted in resident_bytes() while the
  // caller holds it.
  std::shared_ptr<const Mesh> get(ObjectId id, uint32_t level, const EntryMeta& meta, FetchStats& stats);

  // What a Prefetcher over buffer() loads the level with: it reads and decodes as get() does,
  // counting into prefetched(). REQUIRES: loads_in_flight >= 2 when it runs beside get().
  // Thread-safe; the store must outlive every loader.
  ItemLoader loader(ObjectId id, uint32_t level);
  // The I/O, decode and bytes of the loads loader() made.
  FetchStats prefetched() const;

  // Bytes held now: everything reserved in the budget plus uncached meshes still held.
  uint64_t resident_bytes() const;
  // The largest resident_bytes() seen at any get(), counting a load's encoded and decoded bytes
  // while it is in flight.
  uint64_t peak_resident_bytes() const { return peak_.load(); }
  const MemoryBudget& budget() const { return budget_; }
  BufferManager& buffer() { return *buffer_; }
  const World& world() const { return world_; }
  const LevelSource& source() const { return *source_; }

  static CacheKey key(ObjectId id, uint32_t level) { return (uint64_t(id) << 32) | level; }
  static ObjectId object_of(CacheKey key) { return static_cast<ObjectId>(key >> 32); }

 private:
  const World& world_;
  std::unique_ptr<LevelSource> source_;
  uint64_t load_headroom_ = 0;  // the largest encoded level plus its decoded size
  MemoryBudget budget_;         // the caller's budget less load_headroom_
  uint64_t directory_bytes_ = 0;  // the world's directory and the source's bound
  std::unique_ptr<BufferManager> buffer_;
  std::weak_ptr<const Mesh> transient_;  // the last uncached mesh handed out
  uint64_t transient_bytes_ = 0;
  std::atomic<uint64_t> peak_{0};
  mutable std::mutex prefetched_mutex_;
  FetchStats prefetched_;

  LoadedItem load(ObjectId id, uint32_t level, FetchStats& stats);
  void raise_peak(uint64_t bytes);
};

}  // namespace cellwalk
