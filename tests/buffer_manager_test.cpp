// Tests of MemoryBudget and BufferManager: the budget is never exceeded (peak <= limit), values
// are the loaded ones, and LRU hit/miss/eviction counts equal an oracle simulation.
#include "cellwalk/store/buffer_manager.hpp"

#include <gtest/gtest.h>

#include <list>
#include <random>
#include <thread>

#include "cellwalk/store/memory_budget.hpp"

namespace cellwalk {
namespace {

TEST(MemoryBudget, NeverExceededUnderConcurrentReserveAndRelease) {
  MemoryBudget budget(10'000);
  std::vector<std::thread> threads;
  std::atomic<int> over{0};
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      std::mt19937 rng(t);
      std::vector<uint64_t> held;
      for (int i = 0; i < 20000; ++i) {
        if (held.empty() || rng() % 2) {
          const uint64_t bytes = 1 + rng() % 3000;
          if (budget.try_reserve(bytes)) held.push_back(bytes);
        } else {
          budget.release(held.back());
          held.pop_back();
        }
        if (budget.used() > budget.limit()) ++over;
      }
      for (uint64_t bytes : held) budget.release(bytes);
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(over, 0);
  EXPECT_LE(budget.peak(), budget.limit());
  EXPECT_GT(budget.peak(), budget.limit() / 2);  // the threads did fill it
  EXPECT_EQ(budget.used(), 0u);
}

TEST(MemoryBudget, PeakIsExactAndUnlimitedAcceptsAll) {
  MemoryBudget budget(100);
  EXPECT_TRUE(budget.try_reserve(60));
  EXPECT_FALSE(budget.try_reserve(41));
  EXPECT_TRUE(budget.try_reserve(40));
  budget.release(100);
  EXPECT_TRUE(budget.try_reserve(10));
  EXPECT_EQ(budget.peak(), 100u);
  EXPECT_EQ(budget.used(), 10u);
  MemoryBudget unlimited;
  EXPECT_TRUE(unlimited.try_reserve(uint64_t(1) << 50));
  EXPECT_TRUE(unlimited.could_fit(uint64_t(1) << 60));
}

// An item whose bytes are a function of its key, so a returned value can be checked.
uint64_t size_of(CacheKey key) { return 100 + (key * 7919) % 900; }

ItemLoader loader_for(CacheKey key, std::atomic<int>* loads = nullptr) {
  return [key, loads] {
    if (loads) ++*loads;
    auto value = std::make_shared<std::vector<uint8_t>>(size_of(key), uint8_t(key));
    return LoadedItem{value, size_of(key)};
  };
}

bool holds(const CacheResult& r, CacheKey key) {
  auto v = BufferManager::get_as<std::vector<uint8_t>>(r);
  return v && v->size() == size_of(key) && (*v)[0] == uint8_t(key) && v->back() == uint8_t(key);
}

// A byte-budgeted LRU cache simulated from the definition.
struct LruOracle {
  uint64_t limit, used = 0, hits = 0, misses = 0, evictions = 0, transient = 0;
  std::list<CacheKey> order;  // front = least recent
  void get(CacheKey key) {
    auto it = std::find(order.begin(), order.end(), key);
    if (it != order.end()) {
      ++hits;
      order.splice(order.end(), order, it);
      return;
    }
    ++misses;
    if (size_of(key) > limit) {
      ++transient;
      return;
    }
    while (used + size_of(key) > limit) {
      used -= size_of(order.front());
      order.pop_front();
      ++evictions;
    }
    used += size_of(key);
    order.push_back(key);
  }
};

// Li & Chiang's hybrid cache: a prefetch evicts only what the hybrid order puts before it (an
// older frame, or its own frame and less relevant), never what the frame draws (relevance c);
// touch() re-stamps a resident item as this frame's. Under LRU a prefetch evicts as a get does.
TEST(BufferManager, HybridPrefetchNeverDisplacesWhatRanksAboveIt) {
  auto fill = [](BufferManager& cache, MemoryBudget& budget, uint64_t frame) {
    std::vector<CacheKey> keys;
    for (CacheKey key = 0; budget.used() + size_of(key) <= budget.limit(); ++key) {
      cache.get(key, EntryMeta{.relevance = 255.0f, .frame = frame}, loader_for(key));
      keys.push_back(key);
    }
    return keys;
  };
  constexpr uint64_t kFull = 2290;  // keys 0-4 exactly: any admission must evict
  MemoryBudget budget(kFull);
  BufferManager cache(budget, make_hybrid_relevance_policy());
  const std::vector<CacheKey> drawn = fill(cache, budget, 1);
  ASSERT_EQ(budget.used(), kFull);
  const CacheKey guess = 900, later = 1800;  // 100 bytes each, as key 0
  ASSERT_EQ(size_of(guess), size_of(drawn[0]));
  EXPECT_FALSE(cache.prefetch(guess, EntryMeta{.relevance = 10.0f, .frame = 1}, loader_for(guess)));
  for (CacheKey key : drawn) EXPECT_TRUE(cache.contains(key)) << key;
  // Frame 2 draws all but the first; the first is now the oldest and gives way to a frame-2 guess.
  for (size_t i = 1; i < drawn.size(); ++i) EXPECT_TRUE(cache.touch(drawn[i], EntryMeta{.relevance = 255.0f, .frame = 2}));
  EXPECT_FALSE(cache.touch(guess, EntryMeta{.frame = 2}));
  EXPECT_TRUE(cache.prefetch(guess, EntryMeta{.relevance = 10.0f, .frame = 2}, loader_for(guess)));
  EXPECT_FALSE(cache.contains(drawn[0]));
  for (size_t i = 1; i < drawn.size(); ++i) EXPECT_TRUE(cache.contains(drawn[i])) << i;
  // A second, less relevant guess of frame 2 cannot displace the first.
  EXPECT_FALSE(cache.prefetch(later, EntryMeta{.relevance = 5.0f, .frame = 2}, loader_for(later)));
  EXPECT_TRUE(cache.contains(guess));
  EXPECT_LE(budget.peak(), kFull);

  MemoryBudget lru_budget(kFull);
  BufferManager lru(lru_budget, make_lru_policy());
  fill(lru, lru_budget, 1);
  EXPECT_TRUE(lru.prefetch(guess, EntryMeta{}, loader_for(guess)));
  EXPECT_FALSE(lru.contains(0));
}

// Bytes a caller charges beside the cache (vLOD's resident set): cached items that nobody holds
// make room, least recently used first; a held item stays; more than the budget is refused.
TEST(BufferManager, ReserveEvictsWhatNobodyHolds) {
  MemoryBudget budget(3000);
  BufferManager cache(budget, make_lru_policy());
  for (CacheKey key = 0; key < 20 && budget.used() + size_of(key) <= 3000; ++key) cache.get(key, {}, loader_for(key));
  const uint64_t cached = budget.used();
  ASSERT_GT(cached, 2000u);
  const CacheResult held = cache.get(1, {}, loader_for(1));  // the most recent: kept
  EXPECT_FALSE(budget.try_reserve(1500));                     // a plain reserve fails
  EXPECT_TRUE(cache.reserve(1500));
  EXPECT_LE(budget.used(), 3000u);
  EXPECT_GE(budget.used(), 1500u + size_of(1));
  EXPECT_TRUE(cache.contains(1));
  EXPECT_FALSE(cache.contains(0));  // the least recently used went first
  EXPECT_FALSE(cache.reserve(3000 - 1500 - size_of(1) + 1));  // the held item cannot go
  budget.release(1500);
  EXPECT_FALSE(cache.reserve(3001));
  EXPECT_LE(budget.peak(), 3000u);
}

TEST(BufferManager, LruCountsMatchOracleAndBudgetHolds) {
  for (uint64_t limit : {900u, 3000u, 12000u}) {
    MemoryBudget budget(limit);
    BufferManager cache(budget, make_lru_policy());
    LruOracle oracle{limit};
    std::mt19937 rng(limit);
    for (int i = 0; i < 20000; ++i) {
      // Skewed keys: a hot set and a long tail.
      const CacheKey key = rng() % 4 ? rng() % 20 : rng() % 200;
      const CacheResult r = cache.get(key, {}, loader_for(key));
      oracle.get(key);
      ASSERT_TRUE(holds(r, key));
      ASSERT_LE(budget.used(), limit);
    }
    const BufferCounters c = cache.counters();
    EXPECT_EQ(c.hits, oracle.hits) << limit;
    EXPECT_EQ(c.misses, oracle.misses);
    EXPECT_EQ(c.evictions, oracle.evictions);
    EXPECT_EQ(c.transient, oracle.transient);
    EXPECT_EQ(cache.resident_bytes(), oracle.used);
    EXPECT_LE(budget.peak(), limit);
  }
}

TEST(BufferManager, HeldItemsAreNeverEvictedAndOverflowIsTransient) {
  MemoryBudget budget(3000);
  BufferManager cache(budget, make_lru_policy());
  std::vector<CacheResult> held;
  uint64_t used = 0;
  CacheKey key = 0;
  for (; used + size_of(key) <= 3000; ++key) {
    held.push_back(cache.get(key, {}, loader_for(key)));
    used += size_of(key);
  }
  const CacheResult overflow = cache.get(key, {}, loader_for(key));
  EXPECT_TRUE(holds(overflow, key));
  EXPECT_FALSE(overflow.cached);
  EXPECT_EQ(cache.counters().transient, 1u);
  EXPECT_EQ(cache.counters().evictions, 0u);
  EXPECT_FALSE(cache.erase(0));  // held
  for (CacheKey k = 0; k < held.size(); ++k) EXPECT_TRUE(holds(held[k], k));
  held.clear();
  const CacheResult admitted = cache.get(key, {}, loader_for(key));
  EXPECT_TRUE(admitted.cached);
  EXPECT_GE(cache.counters().evictions, 1u);
  EXPECT_LE(budget.peak(), 3000u);
}

TEST(BufferManager, PinnedItemSurvivesAndOversizeItemIsTransient) {
  MemoryBudget budget(2000);
  BufferManager cache(budget, make_dov_policy());
  cache.get(1, EntryMeta{.dov = 0.0f}, loader_for(1));  // lowest DoV: first victim but pinned
  cache.pin(1);
  for (CacheKey k = 2; k < 50; ++k) cache.get(k, EntryMeta{.dov = 0.5f}, loader_for(k));
  EXPECT_TRUE(cache.contains(1));
  EXPECT_FALSE(cache.erase(1));
  cache.unpin(1);
  EXPECT_TRUE(cache.erase(1));
  const CacheResult huge = cache.get(99, {}, [] {
    return LoadedItem{std::make_shared<int>(1), 5000};
  });
  EXPECT_FALSE(huge.cached);
  EXPECT_LE(budget.peak(), 2000u);
}

TEST(BufferManager, LoaderErrorsReachTheCallerAndAreNotCached) {
  MemoryBudget budget(10000);
  BufferManager cache(budget, make_lru_policy());
  EXPECT_THROW(cache.get(7, {}, []() -> LoadedItem { throw std::runtime_error("disk on fire"); }),
               std::runtime_error);
  EXPECT_FALSE(cache.contains(7));
  EXPECT_TRUE(holds(cache.get(7, {}, loader_for(7)), 7));
  EXPECT_EQ(budget.used(), size_of(7));
}

TEST(BufferManager, ConcurrentMissesOnOneKeyLoadOnce) {
  MemoryBudget budget(10000);
  BufferManager cache(budget, make_lru_policy());
  std::atomic<int> loads{0};
  auto slow = [&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    return loader_for(3, &loads)();
  };
  std::vector<std::thread> threads;
  std::atomic<int> good{0};
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] { good += holds(cache.get(3, {}, slow), 3); });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(loads, 1);
  EXPECT_EQ(good, 4);
}

// Two managers with different policies share one budget, four threads, random sizes.
TEST(BufferManager, SharedBudgetHoldsUnderConcurrentRandomAccess) {
  MemoryBudget budget(6000);
  BufferManager geometry(budget, make_dov_time_policy());
  BufferManager index(budget, make_distance_priority_lru_policy());
  std::vector<std::thread> threads;
  std::atomic<int> wrong{0};
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      std::mt19937 rng(t);
      for (int i = 0; i < 5000; ++i) {
        const CacheKey key = rng() % 100;
        BufferManager& cache = rng() % 2 ? geometry : index;
        if (i % 500 == 0) cache.begin_query({.frame = uint64_t(i)});
        const CacheResult r = cache.get(key, EntryMeta{.dov = float(key % 10) / 10}, loader_for(key));
        if (!holds(r, key)) ++wrong;
        if (budget.used() > budget.limit()) ++wrong;
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(wrong, 0);
  EXPECT_LE(budget.peak(), 6000u);
  const BufferCounters g = geometry.counters(), x = index.counters();
  EXPECT_EQ(g.hits + g.misses + x.hits + x.misses, 20000u);
  EXPECT_EQ(budget.used(), geometry.resident_bytes() + index.resident_bytes());
}

}  // namespace
}  // namespace cellwalk
