// BufferManager: a cache of variable-size items under a shared MemoryBudget, with a pluggable
// ReplacementPolicy (HDoV thesis digest §2.1 "Buffer Manager", §3.4, §3.11; seeds/003 hybrid
// cache). Several managers (index pages, decoded geometry, visibility sets, each with its own
// policy) may share one MemoryBudget; each evicts only its own items.
//
// Items are type-erased (shared_ptr<const void>) with a byte size the loader reports; the caller
// knows the type from its key space (see get_as). The budget counts an item from admission until
// it is evicted or erased, and an item is never evicted or erased while a caller still holds a
// handle to it, so memory in the cache or in callers' hands stays within the budget.
//
// When an item does not fit (it is larger than the whole budget, or everything else resident is
// pinned, in use or belongs to another manager), get() still returns the loaded value but with
// cached == false: a transient value, not counted in the budget and freed when the caller drops
// it. A caller bound to the budget treats that as a failed fetch (stall, coarser LOD, skip).
//
// Thread-safety: all members may be called concurrently. One mutex guards the cache; loaders run
// without it. Concurrent misses on one key load it once (the later callers wait for the first).
#pragma once

#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>

#include "cellwalk/store/memory_budget.hpp"
#include "cellwalk/store/replacement_policy.hpp"

namespace cellwalk {

using CacheHandle = std::shared_ptr<const void>;

struct LoadedItem {
  CacheHandle value;  // REQUIRES: the loader keeps no other reference to it
  uint64_t bytes = 0;  // what the item costs the budget
};
// Reads and decodes one item. May throw; the error reaches every caller waiting for the key.
using ItemLoader = std::function<LoadedItem()>;

struct CacheResult {
  CacheHandle value;
  bool hit = false;     // the item was resident when asked for
  bool cached = false;  // the item is resident (false: a transient value, see the class comment)
};

struct BufferCounters {
  uint64_t hits = 0;          // get() found the item resident
  uint64_t misses = 0;        // get() did not (including waits for another caller's load)
  uint64_t loads = 0;         // loader calls (demand and prefetch)
  uint64_t prefetches = 0;    // loader calls made by prefetch()
  uint64_t evictions = 0;     // items evicted to make room
  uint64_t transient = 0;     // loaded items that could not be admitted
  uint64_t bytes_loaded = 0;  // sum of LoadedItem::bytes over loads
};

class BufferManager {
 public:
  // REQUIRES: `budget` outlives the manager.
  BufferManager(MemoryBudget& budget, std::unique_ptr<ReplacementPolicy> policy);
  // Releases every resident item's bytes. REQUIRES: no other thread uses the manager.
  ~BufferManager();
  BufferManager(const BufferManager&) = delete;
  BufferManager& operator=(const BufferManager&) = delete;

  // Returns the item for `key`, calling `loader` on a miss and evicting victims until the budget
  // admits it. `meta` goes to the policy (insert or access). Throws what the loader throws.
  CacheResult get(CacheKey key, const EntryMeta& meta, const ItemLoader& loader);

  // Typed access: REQUIRES the key's items were loaded as T.
  template <class T>
  static std::shared_ptr<const T> get_as(const CacheResult& result) {
    return std::static_pointer_cast<const T>(result.value);
  }

  // Loads `key` if it is neither resident nor being loaded and admits it; no hit/miss is counted.
  // Returns whether the item is resident afterwards.
  bool prefetch(CacheKey key, const EntryMeta& meta, const ItemLoader& loader);

  bool contains(CacheKey key) const;
  // Counts as an access of a resident item with `meta`, without handing it out (e.g. to mark
  // what a frame will draw before a prefetch runs); false, doing nothing, if it is not resident.
  bool touch(CacheKey key, const EntryMeta& meta);
  // Whether `key` is resident or being loaded by some caller.
  bool resident_or_loading(CacheKey key) const;
  // Reserves `bytes` in the budget for the caller (data it holds beside the cache), evicting
  // items nobody holds as the policy chooses until they fit. Returns false, evicting nothing,
  // when they cannot fit even so. The caller releases them with budget().release(bytes).
  bool reserve(uint64_t bytes);
  // Removes `key`. Returns false if it is not resident, or pinned or held by a caller (kept).
  bool erase(CacheKey key);
  // A pinned item is never evicted (e.g. the R-tree root). REQUIRES: key is resident.
  void pin(CacheKey key);
  void unpin(CacheKey key);
  // Tells the policy a new query or frame begins (DPLRU re-scores here).
  void begin_query(const QueryContext& context);

  uint64_t resident_bytes() const;
  size_t resident_items() const;
  BufferCounters counters() const;
  void reset_counters();
  MemoryBudget& budget() const { return budget_; }

 private:
  struct Item {
    CacheHandle value;
    uint64_t bytes = 0;
    uint32_t pins = 0;
  };
  using Pending = std::shared_future<LoadedItem>;
  enum class Kind { kDemand, kPrefetch };

  CacheResult load(CacheKey key, const EntryMeta& meta, const ItemLoader& loader, Kind kind,
                   std::unique_lock<std::mutex>& lock);
  bool admit(CacheKey key, const EntryMeta& meta, const LoadedItem& item, Kind kind);
  std::optional<CacheKey> evictable_victim();
  void evict(CacheKey key);
  void remove(std::unordered_map<CacheKey, Item>::iterator it);

  MemoryBudget& budget_;
  std::unique_ptr<ReplacementPolicy> policy_;
  mutable std::mutex mutex_;
  std::unordered_map<CacheKey, Item> items_;
  std::unordered_map<CacheKey, Pending> loading_;
  uint64_t resident_bytes_ = 0;
  BufferCounters counters_;
};

}  // namespace cellwalk
