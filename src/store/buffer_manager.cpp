// BufferManager: budgeted cache with pluggable replacement (HDoV thesis digest §2.1 "Buffer
// Manager"; §3.4 DPLRU, §3.11 DoV/DT; seeds/003 hybrid cache).
#include "cellwalk/store/buffer_manager.hpp"

#include <vector>

#include "cellwalk/core/error.hpp"

namespace cellwalk {

BufferManager::BufferManager(MemoryBudget& budget, std::unique_ptr<ReplacementPolicy> policy)
    : budget_(budget), policy_(std::move(policy)) {}

BufferManager::~BufferManager() { budget_.release(resident_bytes_); }

CacheResult BufferManager::get(CacheKey key, const EntryMeta& meta, const ItemLoader& loader) {
  std::unique_lock lock(mutex_);
  if (auto it = items_.find(key); it != items_.end()) {
    policy_->on_access(key, meta);
    ++counters_.hits;
    return {it->second.value, true, true};
  }
  ++counters_.misses;
  return load(key, meta, loader, Kind::kDemand, lock);
}

bool BufferManager::prefetch(CacheKey key, const EntryMeta& meta, const ItemLoader& loader) {
  std::unique_lock lock(mutex_);
  if (items_.contains(key)) return true;
  if (loading_.contains(key)) return false;
  return load(key, meta, loader, Kind::kPrefetch, lock).cached;
}

// REQUIRES: `lock` holds mutex_ and `key` is not resident. Runs the loader without the lock;
// a second caller for the same key waits for the first one's result instead of loading again.
CacheResult BufferManager::load(CacheKey key, const EntryMeta& meta, const ItemLoader& loader,
                                Kind kind, std::unique_lock<std::mutex>& lock) {
  if (auto pending = loading_.find(key); pending != loading_.end()) {
    Pending result = pending->second;
    lock.unlock();
    LoadedItem item = result.get();
    lock.lock();
    if (auto it = items_.find(key); it != items_.end()) {
      policy_->on_access(key, meta);
      return {it->second.value, false, true};
    }
    return {item.value, false, false};
  }

  std::promise<LoadedItem> promise;
  loading_.emplace(key, promise.get_future().share());
  ++counters_.loads;
  if (kind == Kind::kPrefetch) ++counters_.prefetches;
  lock.unlock();
  LoadedItem item;
  try {
    item = loader();
  } catch (...) {
    lock.lock();
    loading_.erase(key);
    promise.set_exception(std::current_exception());
    throw;
  }
  lock.lock();
  loading_.erase(key);
  counters_.bytes_loaded += item.bytes;
  const bool cached = admit(key, meta, item, kind);
  if (!cached) ++counters_.transient;
  promise.set_value(item);
  return {std::move(item.value), false, cached};
}

// Evicts victims until the budget takes the item. May evict and still fail when the space freed
// is not enough (everything left is pinned, in use or another manager's).
bool BufferManager::admit(CacheKey key, const EntryMeta& meta, const LoadedItem& item, Kind kind) {
  if (!budget_.could_fit(item.bytes)) return false;
  while (!budget_.try_reserve(item.bytes)) {
    const std::optional<CacheKey> victim = evictable_victim();
    if (!victim || (kind == Kind::kPrefetch && !policy_->yields_to_prefetch(*victim, meta))) return false;
    evict(*victim);
  }
  items_.emplace(key, Item{item.value, item.bytes, 0});
  resident_bytes_ += item.bytes;
  policy_->on_insert(key, meta);
  return true;
}

// The policy's victim, skipping items a caller still holds. use_count() is exact enough here:
// the cache's own reference is copied only under mutex_, so a count of 1 cannot grow meanwhile.
std::optional<CacheKey> BufferManager::evictable_victim() {
  std::vector<CacheKey> in_use;
  std::optional<CacheKey> victim;
  while ((victim = policy_->victim())) {
    if (items_.at(*victim).value.use_count() == 1) break;
    policy_->pin(*victim);
    in_use.push_back(*victim);
  }
  for (CacheKey key : in_use) policy_->unpin(key);
  return victim;
}

void BufferManager::evict(CacheKey key) {
  remove(items_.find(key));
  ++counters_.evictions;
}

void BufferManager::remove(std::unordered_map<CacheKey, Item>::iterator it) {
  budget_.release(it->second.bytes);
  resident_bytes_ -= it->second.bytes;
  policy_->on_erase(it->first);
  items_.erase(it);
}

bool BufferManager::contains(CacheKey key) const {
  std::lock_guard lock(mutex_);
  return items_.contains(key);
}

bool BufferManager::resident_or_loading(CacheKey key) const {
  std::lock_guard lock(mutex_);
  return items_.contains(key) || loading_.contains(key);
}

bool BufferManager::reserve(uint64_t bytes) {
  std::lock_guard lock(mutex_);
  if (!budget_.could_fit(bytes)) return false;
  if (budget_.limit() != 0) {  // refuse before evicting anything when even eviction cannot make room
    uint64_t freeable = 0;
    for (const auto& [key, item] : items_)
      if (item.pins == 0 && item.value.use_count() == 1) freeable += item.bytes;
    if (budget_.used() - std::min(budget_.used(), freeable) + bytes > budget_.limit()) return false;
  }
  while (!budget_.try_reserve(bytes)) {
    const std::optional<CacheKey> victim = evictable_victim();
    if (!victim) return false;
    evict(*victim);
  }
  return true;
}

bool BufferManager::touch(CacheKey key, const EntryMeta& meta) {
  std::lock_guard lock(mutex_);
  if (!items_.contains(key)) return false;
  policy_->on_access(key, meta);
  return true;
}

bool BufferManager::erase(CacheKey key) {
  std::lock_guard lock(mutex_);
  auto it = items_.find(key);
  if (it == items_.end() || it->second.pins > 0 || it->second.value.use_count() > 1) return false;
  remove(it);
  return true;
}

void BufferManager::pin(CacheKey key) {
  std::lock_guard lock(mutex_);
  auto it = items_.find(key);
  if (it == items_.end()) fail("BufferManager::pin", "key " + std::to_string(key) + " is not resident");
  ++it->second.pins;
  policy_->pin(key);
}

void BufferManager::unpin(CacheKey key) {
  std::lock_guard lock(mutex_);
  auto it = items_.find(key);
  if (it == items_.end() || it->second.pins == 0) {
    fail("BufferManager::unpin", "key " + std::to_string(key) + " is not pinned");
  }
  --it->second.pins;
  policy_->unpin(key);
}

void BufferManager::begin_query(const QueryContext& context) {
  std::lock_guard lock(mutex_);
  policy_->on_query(context);
}

uint64_t BufferManager::resident_bytes() const {
  std::lock_guard lock(mutex_);
  return resident_bytes_;
}

size_t BufferManager::resident_items() const {
  std::lock_guard lock(mutex_);
  return items_.size();
}

BufferCounters BufferManager::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

void BufferManager::reset_counters() {
  std::lock_guard lock(mutex_);
  counters_ = {};
}

}  // namespace cellwalk
