// Hybrid cache model of Li & Chiang, "Data Management for Visualizing Large Virtual
// Environments" (ISMIP 1999), seeds/003 "Data Caching: Hybrid Cache Model":
//   objects retrieved at different frames are replaced in LRU order of their frames;
//   objects retrieved at the same frame are replaced in order of relevance, lowest first.
// The frame of an entry is EntryMeta::frame of its latest request; ties in relevance go to the
// least recently used entry.
#include "cellwalk/store/replacement_policy.hpp"

namespace cellwalk {
namespace {

class HybridRelevancePolicy final : public ScoredPolicy {
  Score score(const Entry& entry) const override {
    return {static_cast<double>(entry.meta.frame), static_cast<double>(entry.meta.relevance),
            static_cast<double>(entry.last_access)};
  }
  // The newcomer ranks as the most recent access of its frame and relevance.
  bool yields_to_prefetch(CacheKey key, const EntryMeta& newcomer) const override {
    Entry candidate;
    candidate.meta = newcomer;
    candidate.last_access = UINT64_MAX;
    return entries().at(key).score < score(candidate);
  }
};

}  // namespace

std::unique_ptr<ReplacementPolicy> make_hybrid_relevance_policy() {
  return std::make_unique<HybridRelevancePolicy>();
}

}  // namespace cellwalk
