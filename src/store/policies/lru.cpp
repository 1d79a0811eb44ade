// LRU replacement: the baseline of the HDoV thesis (digest §3.4, §3.11) and of Li & Chiang
// (seeds/003). A list in access order (front = least recent) and a hash map into it: O(1).
#include <list>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/replacement_policy.hpp"

namespace cellwalk {
namespace {

class LruPolicy final : public ReplacementPolicy {
 public:
  void on_insert(CacheKey key, const EntryMeta&) override {
    auto [it, inserted] = entries_.try_emplace(key);
    if (!inserted) fail("ReplacementPolicy", "key " + std::to_string(key) + " inserted twice");
    it->second.position = order_.insert(order_.end(), key);
  }

  void on_access(CacheKey key, const EntryMeta&) override {
    Entry& entry = find(key);
    if (entry.pins == 0) order_.splice(order_.end(), order_, entry.position);
  }

  void on_erase(CacheKey key) override {
    Entry& entry = find(key);
    if (entry.pins == 0) order_.erase(entry.position);
    entries_.erase(key);
  }

  std::optional<CacheKey> victim() const override {
    if (order_.empty()) return std::nullopt;
    return order_.front();
  }

  // A pinned entry leaves the list; unpinning counts as an access (it was in use until now).
  void pin(CacheKey key) override {
    Entry& entry = find(key);
    if (entry.pins++ == 0) order_.erase(entry.position);
  }

  void unpin(CacheKey key) override {
    Entry& entry = find(key);
    if (entry.pins == 0) fail("ReplacementPolicy", "key " + std::to_string(key) + " is not pinned");
    if (--entry.pins == 0) entry.position = order_.insert(order_.end(), key);
  }

  size_t size() const override { return entries_.size(); }

 private:
  struct Entry {
    std::list<CacheKey>::iterator position;  // valid while pins == 0
    uint32_t pins = 0;
  };

  Entry& find(CacheKey key) {
    auto it = entries_.find(key);
    if (it == entries_.end()) fail("ReplacementPolicy", "key " + std::to_string(key) + " is not tracked");
    return it->second;
  }

  std::list<CacheKey> order_;
  std::unordered_map<CacheKey, Entry> entries_;
};

}  // namespace

std::unique_ptr<ReplacementPolicy> make_lru_policy() { return std::make_unique<LruPolicy>(); }

}  // namespace cellwalk
