// ScoredPolicy: the ordered-set mechanism shared by the DPLRU, DoV, DoV-Time and hybrid policies
// (HDoV thesis digest §3.11: "a hash map nodeID → nodePtr plus an ordered map list").
#include "cellwalk/core/error.hpp"
#include "cellwalk/store/replacement_policy.hpp"

namespace cellwalk {

ScoredPolicy::Entry& ScoredPolicy::find(CacheKey key) {
  auto it = entries_.find(key);
  if (it == entries_.end()) fail("ReplacementPolicy", "key " + std::to_string(key) + " is not tracked");
  return it->second;
}

void ScoredPolicy::touch(Entry& entry, const EntryMeta& meta) {
  entry.meta = meta;
  entry.last_access = ++access_clock_;
  entry.last_query = query_clock_;
}

void ScoredPolicy::order_insert(CacheKey key, Entry& entry) {
  entry.score = score(entry);
  if (entry.pins == 0) order_.emplace(entry.score, key);
}

void ScoredPolicy::order_erase(CacheKey key, const Entry& entry) {
  if (entry.pins == 0) order_.erase({entry.score, key});
}

void ScoredPolicy::on_insert(CacheKey key, const EntryMeta& meta) {
  auto [it, inserted] = entries_.try_emplace(key);
  if (!inserted) fail("ReplacementPolicy", "key " + std::to_string(key) + " inserted twice");
  touch(it->second, meta);
  order_insert(key, it->second);
}

void ScoredPolicy::on_access(CacheKey key, const EntryMeta& meta) {
  Entry& entry = find(key);
  order_erase(key, entry);
  touch(entry, meta);
  order_insert(key, entry);
}

void ScoredPolicy::on_erase(CacheKey key) {
  order_erase(key, find(key));
  entries_.erase(key);
}

std::optional<CacheKey> ScoredPolicy::victim() const {
  if (order_.empty()) return std::nullopt;
  return order_.begin()->second;
}

void ScoredPolicy::pin(CacheKey key) {
  Entry& entry = find(key);
  order_erase(key, entry);
  ++entry.pins;
}

void ScoredPolicy::unpin(CacheKey key) {
  Entry& entry = find(key);
  if (entry.pins == 0) fail("ReplacementPolicy", "key " + std::to_string(key) + " is not pinned");
  if (--entry.pins > 0) return;
  touch(entry, entry.meta);
  order_insert(key, entry);
}

void ScoredPolicy::rescore_all() {
  order_.clear();
  for (auto& [key, entry] : entries_) order_insert(key, entry);
}

}  // namespace cellwalk
