// Tests of the replacement policies against a brute-force oracle that computes the victim from
// each policy's definition (HDoV thesis digest §3.4, §3.11; seeds/003) by scanning every entry.
#include "cellwalk/store/replacement_policy.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <random>

namespace cellwalk {
namespace {

// The oracle's view of an entry: what the definitions refer to.
struct OracleEntry {
  EntryMeta meta;
  uint64_t last_access = 0;  // accesses counted from 1 (insert, hit, last unpin)
  uint64_t last_query = 0;   // queries seen before the last access
  uint32_t pins = 0;
};

// State shared by all oracles; `victim` holds one definition.
struct Oracle {
  std::map<CacheKey, OracleEntry> entries;
  uint64_t clock = 0;
  uint64_t queries = 0;
  std::function<void(Oracle&, const QueryContext&)> on_query = [](Oracle&, const QueryContext&) {};
  // Returns the key with the smallest tuple; ties by smaller key (std::map order).
  std::function<std::optional<CacheKey>(const Oracle&)> victim;

  void access(CacheKey key, const EntryMeta& meta) {
    entries[key].meta = meta;
    entries[key].last_access = ++clock;
    entries[key].last_query = queries;
  }
};

template <class Tuple>
std::optional<CacheKey> smallest(const Oracle& o, const std::function<Tuple(const OracleEntry&)>& f) {
  std::optional<CacheKey> best;
  Tuple best_value{};
  for (const auto& [key, e] : o.entries) {
    if (e.pins > 0) continue;
    const Tuple value = f(e);
    if (!best || value < best_value) best = key, best_value = value;
  }
  return best;
}

using Pair = std::pair<double, double>;
using Triple = std::tuple<double, double, double>;

Oracle lru_oracle() {
  Oracle o;
  o.victim = [](const Oracle& o) {
    return smallest<double>(o, [](const OracleEntry& e) { return double(e.last_access); });
  };
  return o;
}

Oracle dov_time_oracle(double kappa) {
  Oracle o;
  // §3.11: f(DoV, T) = DoV + κ·T, evict the smallest; ties by least recent access.
  o.victim = [kappa](const Oracle& o) {
    return smallest<Pair>(o, [kappa](const OracleEntry& e) {
      return Pair{e.meta.dov + kappa * double(e.last_access), double(e.last_access)};
    });
  };
  return o;
}

Oracle hybrid_oracle() {
  Oracle o;
  o.victim = [](const Oracle& o) {
    return smallest<Triple>(o, [](const OracleEntry& e) {
      return Triple{double(e.meta.frame), e.meta.relevance, double(e.last_access)};
    });
  };
  return o;
}

// DPLRU: at each query, min-max ranges of P, DIST(Q, BB) and QN over the unpinned entries are
// taken; the victim is the largest f = α·pp + β·pd + γ·pl with those ranges (ties: least recent).
struct DplruState {
  BlockBox cell;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
};

Oracle dplru_oracle(std::shared_ptr<DplruState> s) {
  Oracle o;
  auto values = [s](const Oracle& o, const OracleEntry& e) {
    return std::array<double, 3>{double(e.meta.level), double(block_distance(s->cell, e.meta.box)),
                                 double(o.queries - e.last_query)};
  };
  o.on_query = [s, values](Oracle& o, const QueryContext& q) {
    ++o.queries;
    s->cell = q.cell;
    for (int i = 0; i < 3; ++i) s->lo[i] = INFINITY, s->hi[i] = -INFINITY;
    for (const auto& [key, e] : o.entries) {
      if (e.pins > 0) continue;
      const auto v = values(o, e);
      for (int i = 0; i < 3; ++i) s->lo[i] = std::min(s->lo[i], v[i]), s->hi[i] = std::max(s->hi[i], v[i]);
    }
  };
  o.victim = [s, values](const Oracle& o) {
    return smallest<Pair>(o, [&](const OracleEntry& e) {
      const auto v = values(o, e);
      double n[3];
      for (int i = 0; i < 3; ++i) n[i] = s->hi[i] > s->lo[i] ? (v[i] - s->lo[i]) / (s->hi[i] - s->lo[i]) : 0.0;
      const double f = (1.0 / 3.0) * n[0] + (1.0 / 3.0) * n[1] + (1.0 / 3.0) * n[2];
      return Pair{-f, double(e.last_access)};
    });
  };
  return o;
}

BlockBox random_box(std::mt19937& rng) {
  BlockBox b;
  for (int i = 0; i < 3; ++i) {
    b.lo[i] = float(rng() % 20);
    b.hi[i] = b.lo[i] + float(rng() % 4);
  }
  return b;
}

EntryMeta random_meta(std::mt19937& rng, uint64_t frame) {
  EntryMeta m;
  m.level = rng() % 5;
  m.box = random_box(rng);
  m.dov = float(rng() % 1000) / 1000.0f;
  m.relevance = float(rng() % 8);  // few values: exercises ties
  m.frame = frame;
  return m;
}

// Random inserts, hits, erases, pins, unpins and queries; the victim is compared after each.
void run_against_oracle(ReplacementPolicy& policy, Oracle oracle, uint32_t seed) {
  std::mt19937 rng(seed);
  uint64_t frame = 0;
  for (int step = 0; step < 4000; ++step) {
    const CacheKey key = rng() % 64;
    const bool tracked = oracle.entries.contains(key);
    const int op = rng() % 100;
    if (!tracked && op < 60) {
      const EntryMeta meta = random_meta(rng, frame);
      policy.on_insert(key, meta);
      oracle.access(key, meta);
    } else if (tracked && op < 55) {
      const EntryMeta meta = random_meta(rng, frame);
      policy.on_access(key, meta);
      oracle.access(key, meta);
    } else if (tracked && op < 70) {
      policy.on_erase(key);
      oracle.entries.erase(key);
    } else if (tracked && op < 78) {
      policy.pin(key);
      ++oracle.entries[key].pins;
    } else if (tracked && op < 88 && oracle.entries[key].pins > 0) {
      policy.unpin(key);
      if (--oracle.entries[key].pins == 0) oracle.access(key, oracle.entries[key].meta);
    } else if (op >= 95) {
      const QueryContext query{random_box(rng), ++frame};
      policy.on_query(query);
      oracle.on_query(oracle, query);
    }
    ASSERT_EQ(policy.size(), oracle.entries.size());
    ASSERT_EQ(policy.victim(), oracle.victim(oracle)) << "step " << step;
  }
}

TEST(ReplacementPolicy, LruMatchesOracle) {
  for (uint32_t seed = 0; seed < 5; ++seed) run_against_oracle(*make_lru_policy(), lru_oracle(), seed);
}

TEST(ReplacementPolicy, DovMatchesOracle) {
  for (uint32_t seed = 0; seed < 5; ++seed) run_against_oracle(*make_dov_policy(), dov_time_oracle(0.0), seed);
}

TEST(ReplacementPolicy, DovTimeMatchesOracle) {
  for (uint32_t seed = 0; seed < 5; ++seed) {
    run_against_oracle(*make_dov_time_policy(), dov_time_oracle(0.001), seed);
  }
}

TEST(ReplacementPolicy, HybridRelevanceMatchesOracle) {
  for (uint32_t seed = 0; seed < 5; ++seed) {
    run_against_oracle(*make_hybrid_relevance_policy(), hybrid_oracle(), seed);
  }
}

TEST(ReplacementPolicy, DistancePriorityLruMatchesOracle) {
  for (uint32_t seed = 0; seed < 5; ++seed) {
    run_against_oracle(*make_distance_priority_lru_policy(),
                       dplru_oracle(std::make_shared<DplruState>()), seed);
  }
}

TEST(ReplacementPolicy, BlockDistanceIsTheLargestAxisGap) {
  const BlockBox a{{0, 0, 0}, {1, 1, 1}};
  EXPECT_EQ(block_distance(a, BlockBox{{0.5f, 0.5f, 0.5f}, {3, 3, 3}}), 0.0f);  // overlap
  EXPECT_EQ(block_distance(a, BlockBox{{4, 2, 1}, {5, 3, 1}}), 3.0f);
  EXPECT_EQ(block_distance(BlockBox{{4, 2, 1}, {5, 3, 1}}, a), 3.0f);
}

// The thesis's intent (§3.4): same level and age, the entry far from the query cell goes first;
// the pinned root never goes.
TEST(ReplacementPolicy, DistancePriorityLruEvictsFarBeforeNearAndNeverThePinnedRoot) {
  auto policy = make_distance_priority_lru_policy();
  policy->on_insert(0, EntryMeta{.level = 0, .box = {{0, 0, 0}, {100, 100, 100}}});
  policy->pin(0);
  policy->on_insert(1, EntryMeta{.level = 2, .box = {{50, 0, 0}, {51, 1, 1}}});  // far
  policy->on_insert(2, EntryMeta{.level = 2, .box = {{1, 0, 0}, {2, 1, 1}}});    // near
  policy->on_query({.cell = {{0, 0, 0}, {1, 1, 1}}, .frame = 1});
  EXPECT_EQ(policy->victim(), 1u);
  policy->on_erase(1);
  EXPECT_EQ(policy->victim(), 2u);
  policy->on_erase(2);
  EXPECT_EQ(policy->victim(), std::nullopt);
}

// seeds/003: within the oldest frame, the least relevant object goes first, even if it was
// requested after a more relevant one.
TEST(ReplacementPolicy, HybridEvictsOldestFrameLowestRelevanceFirst) {
  auto policy = make_hybrid_relevance_policy();
  policy->on_insert(1, EntryMeta{.relevance = 5, .frame = 1});
  policy->on_insert(2, EntryMeta{.relevance = 1, .frame = 1});
  policy->on_insert(3, EntryMeta{.relevance = 0, .frame = 2});
  EXPECT_EQ(policy->victim(), 2u);
  policy->on_access(2, EntryMeta{.relevance = 1, .frame = 3});  // requested again in frame 3
  EXPECT_EQ(policy->victim(), 1u);
}

}  // namespace
}  // namespace cellwalk
