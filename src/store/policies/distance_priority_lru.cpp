// Distance-priority LRU (DPLRU) for index nodes: HDoV thesis §4.2.4, digest §3.4.
//   Evict the entry with the largest f = α·pp + β·pd + γ·pl (α = β = γ = 1/3), where pp, pd, pl
//   are the min-max normalised (digest [GAP] answer: over the candidates) level priority
//   P = node level, block distance DIST(Q, BB) to the query cell Q, and age QN. Ties go to the
//   least recently used entry. QN counts queries since the entry was loaded or last hit (reset on
//   a hit: the digest's reading of the LRU intent). Pin the root.
//
// Why scores are frozen per query: with min-max normalisation every insert or eviction can move
// the ranges and so every score, and each query moves Q and ages every entry; no O(log n)
// structure keeps that exact. The thesis ages entries once per query, so this policy does all
// viewer-dependent work there: on_query() advances QN, computes the ranges over the unpinned
// entries and re-scores all of them (O(n log n) per query). Between queries the ranges and Q are
// fixed, an entry's score changes only when it is itself inserted or hit, and every operation is
// O(log n). Entries inserted or hit within a query are scored against the frozen ranges (their
// pp, pd, pl may fall outside [0, 1], which keeps the order linear and exact).
#include <algorithm>
#include <cmath>
#include <limits>

#include "cellwalk/store/replacement_policy.hpp"

namespace cellwalk {

float block_distance(const BlockBox& a, const BlockBox& b) {
  float distance = 0.0f;
  for (int axis = 0; axis < 3; ++axis) {
    const float gap = std::max({0.0f, a.lo[axis] - b.hi[axis], b.lo[axis] - a.hi[axis]});
    distance = std::max(distance, gap);
  }
  return distance;
}

namespace {

// Min-max normalisation of one quantity: (v - min) / (max - min), 0 when the range is empty.
struct Range {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  void add(double v) {
    min = std::min(min, v);
    max = std::max(max, v);
  }
  double normalise(double v) const { return max > min ? (v - min) / (max - min) : 0.0; }
};

class DistancePriorityLruPolicy final : public ScoredPolicy {
 public:
  explicit DistancePriorityLruPolicy(DistancePriorityWeights weights) : weights_(weights) {}

  void on_query(const QueryContext& context) override {
    advance_query_clock();
    query_cell_ = context.cell;
    level_ = distance_ = age_ = Range{};
    for (const auto& [key, entry] : entries()) {
      if (entry.pins > 0) continue;
      level_.add(entry.meta.level);
      distance_.add(block_distance(query_cell_, entry.meta.box));
      age_.add(age(entry));
    }
    rescore_all();
  }

 private:
  double age(const Entry& entry) const {
    return static_cast<double>(query_clock() - entry.last_query);
  }

  // Smallest score is evicted, so the score is (-f, last access).
  Score score(const Entry& entry) const override {
    const double f = weights_.alpha * level_.normalise(entry.meta.level) +
                     weights_.beta * distance_.normalise(block_distance(query_cell_, entry.meta.box)) +
                     weights_.gamma * age_.normalise(age(entry));
    return {-f, static_cast<double>(entry.last_access), 0.0};
  }

  const DistancePriorityWeights weights_;
  BlockBox query_cell_;
  Range level_, distance_, age_;  // over the unpinned entries at the last on_query()
};

}  // namespace

std::unique_ptr<ReplacementPolicy> make_distance_priority_lru_policy(
    DistancePriorityWeights weights) {
  return std::make_unique<DistancePriorityLruPolicy>(weights);
}

}  // namespace cellwalk
