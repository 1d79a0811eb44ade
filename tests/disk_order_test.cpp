// Tests of the disk order (vLOD §3, digest 001 §3.5): total runs against a bit-string count,
// Hamming against dense vectors, exact k-NN lists against all pairs, the heuristic against the
// best of all permutations on small matrices and on planted consecutive-ones matrices.
// The seed's Table 1 on planted matrices is `cellwalk bench disk-order`.
#include "cellwalk/visibility/disk_order.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <numeric>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "experiments/disk_order/planted_matrix.hpp"

namespace cellwalk::visibility {
namespace {

using Rows = std::vector<std::vector<uint32_t>>;

Rows random_rows(Random& random, uint32_t rows, uint32_t columns, double density) {
  Rows m(rows);
  for (auto& row : m)
    for (uint32_t c = 0; c < columns; ++c)
      if (random.chance(density)) row.push_back(c);
  return m;
}

std::vector<uint32_t> shuffled(Random& random, uint32_t n) {
  std::vector<uint32_t> order = identity_order(n);
  for (uint32_t i = n; i > 1; --i) std::swap(order[i - 1], order[size_t(random.integer(0, i - 1))]);
  return order;
}

// The oracle: each row as a string of bits in the permuted order, runs counted as 0→1 steps.
uint64_t runs_by_bits(const Rows& rows, const std::vector<uint32_t>& order) {
  uint64_t runs = 0;
  for (const auto& row : rows) {
    bool previous = false;
    for (uint32_t column : order) {
      const bool bit = std::binary_search(row.begin(), row.end(), column);
      runs += bit && !previous;
      previous = bit;
    }
  }
  return runs;
}

bool is_permutation_of(const std::vector<uint32_t>& order, uint32_t n) {
  std::vector<uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  return sorted == identity_order(n);
}


TEST(DiskOrder, TotalRunsOfTheDigestsExample) {
  const std::string bits = "0011100111010";
  Rows rows(1);
  for (uint32_t c = 0; c < bits.size(); ++c)
    if (bits[c] == '1') rows[0].push_back(c);
  EXPECT_EQ(total_runs(rows, identity_order(uint32_t(bits.size()))), 3u);
}

TEST(DiskOrder, TotalRunsCountsTheRunsOfEveryPermutedRow) {
  Random random(1);
  for (int trial = 0; trial < 200; ++trial) {
    const uint32_t columns = uint32_t(random.integer(1, 40));
    const Rows rows =
        random_rows(random, uint32_t(random.integer(0, 12)), columns, random.uniform());
    const std::vector<uint32_t> order = shuffled(random, columns);
    EXPECT_EQ(total_runs(rows, order), runs_by_bits(rows, order));
  }
}

TEST(DiskOrder, TotalRunsRefusesAnOrderThatIsNoPermutation) {
  const Rows rows = {{0, 2}};
  EXPECT_THROW(total_runs(rows, std::vector<uint32_t>{0, 1, 1}), Error);
  EXPECT_THROW(total_runs(rows, std::vector<uint32_t>{0, 1}), Error);  // row names column 2
  EXPECT_THROW(total_runs(rows, std::vector<uint32_t>{0, 1, 3}), Error);
}

TEST(DiskOrder, HammingIsTheDenseSymmetricDifference) {
  Random random(2);
  for (int trial = 0; trial < 300; ++trial) {
    const uint32_t rows = uint32_t(random.integer(0, 60));
    const Rows pair = random_rows(random, 2, rows, random.uniform());  // two "columns" of row ids
    uint32_t dense = 0;
    for (uint32_t r = 0; r < rows; ++r) {
      const bool u = std::binary_search(pair[0].begin(), pair[0].end(), r);
      const bool v = std::binary_search(pair[1].begin(), pair[1].end(), r);
      dense += (u + v) % 2;
    }
    EXPECT_EQ(hamming(pair[0], pair[1]), dense);
    EXPECT_EQ(hamming(pair[1], pair[0]), dense);
  }
}

TEST(DiskOrder, ColumnsFromRowsTransposes) {
  Random random(3);
  const Rows rows = random_rows(random, 30, 25, 0.3);
  const SparseColumns m = columns_from_rows(rows, 25);
  ASSERT_EQ(m.rows, 30u);
  ASSERT_EQ(m.columns.size(), 25u);
  for (uint32_t r = 0; r < 30; ++r)
    for (uint32_t c = 0; c < 25; ++c)
      EXPECT_EQ(std::binary_search(rows[r].begin(), rows[r].end(), c),
                std::binary_search(m.columns[c].begin(), m.columns[c].end(), r));
  for (const auto& column : m.columns) EXPECT_TRUE(std::is_sorted(column.begin(), column.end()));
  EXPECT_THROW(columns_from_rows({{3, 1}}, 5), Error);
  EXPECT_THROW(columns_from_rows({{1, 5}}, 5), Error);
  EXPECT_THROW(columns_from_rows({{1, 1}}, 5), Error);
}

// All pairs, sorted by (distance, id).
NeighbourLists brute_force_lists(const SparseColumns& m, uint32_t k) {
  NeighbourLists lists(m.columns.size());
  for (uint32_t p = 0; p < m.columns.size(); ++p) {
    for (uint32_t v = 0; v < m.columns.size(); ++v)
      if (v != p) lists[p].push_back({v, hamming(m.columns[p], m.columns[v])});
    std::sort(lists[p].begin(), lists[p].end(), [](const Neighbour& a, const Neighbour& b) {
      return std::pair(a.distance, a.column) < std::pair(b.distance, b.column);
    });
    lists[p].resize(std::min<size_t>(k, lists[p].size()));
  }
  return lists;
}

void expect_same_lists(const NeighbourLists& a, const NeighbourLists& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t p = 0; p < a.size(); ++p) {
    ASSERT_EQ(a[p].size(), b[p].size()) << "column " << p;
    for (size_t i = 0; i < a[p].size(); ++i) {
      EXPECT_EQ(a[p][i].column, b[p][i].column) << "column " << p << " neighbour " << i;
      EXPECT_EQ(a[p][i].distance, b[p][i].distance) << "column " << p << " neighbour " << i;
    }
  }
}

TEST(DiskOrder, ExactListsAreTheBruteForceNearestWithTiesByTheSmallerId) {
  Random random(4);
  for (int trial = 0; trial < 30; ++trial) {
    // Few rows and sparse columns: many equal distances, empty and duplicate columns, and
    // columns sharing no row with each other.
    const uint32_t columns = uint32_t(random.integer(1, 120));
    const Rows rows = random_rows(random, uint32_t(random.integer(0, 10)), columns,
                                  0.03 + 0.3 * random.uniform());
    const SparseColumns m = columns_from_rows(rows, columns);
    DiskOrderOptions options;
    options.k = uint32_t(random.integer(1, 25));
    expect_same_lists(nearest_neighbours(m, options), brute_force_lists(m, options.k));
  }
}

TEST(DiskOrder, SampledListsHoldTrueDistancesAndAreExactWhenTheSampleIsEverything) {
  const PlantedMatrix p = planted_matrix(400, 800, 20, 0.3, 5);
  const SparseColumns m = columns_from_rows(p.rows, 400);
  DiskOrderOptions options;
  options.use_sampling = true;
  options.sample_factor = 5;  // 30 sample columns out of 400
  const NeighbourLists sampled = nearest_neighbours(m, options);
  const NeighbourLists exact = brute_force_lists(m, options.k);
  ASSERT_EQ(sampled.size(), 400u);
  size_t found = 0;
  for (uint32_t c = 0; c < 400; ++c) {
    ASSERT_EQ(sampled[c].size(), options.k);
    for (size_t i = 0; i < sampled[c].size(); ++i) {
      const Neighbour& n = sampled[c][i];
      EXPECT_NE(n.column, c);
      EXPECT_EQ(n.distance, hamming(m.columns[c], m.columns[n.column]));
      if (i > 0) {
        const Neighbour& before = sampled[c][i - 1];
        EXPECT_LT(std::pair(before.distance, before.column), std::pair(n.distance, n.column));
      }
      // Never nearer than the true k-th nearest allows.
      EXPECT_GE(n.distance, exact[c][i].distance);
      found += std::any_of(exact[c].begin(), exact[c].end(),
                           [&](const Neighbour& e) { return e.column == n.column; });
    }
  }
  // The groups of the nearest sample columns hold a good part of the true neighbours.
  EXPECT_GT(found, 400u * options.k / 4);
  options.sample_factor = 1000;  // the sample is every column
  expect_same_lists(nearest_neighbours(m, options), exact);
}

// The smallest R(M) over all column orders, counting run starts directly on bit masks.
uint64_t optimum_runs(const Rows& rows, uint32_t columns) {
  std::vector<uint32_t> mask(columns, 0);  // bit r: row r has a 1 in the column
  for (uint32_t r = 0; r < rows.size(); ++r)
    for (uint32_t c : rows[r]) mask[c] |= 1u << r;
  std::vector<uint32_t> order = identity_order(columns);
  uint64_t best = ~0ull;
  do {
    uint64_t runs = 0;
    uint32_t previous = 0;
    for (uint32_t c : order) {
      runs += std::popcount(mask[c] & ~previous);
      previous = mask[c];
    }
    best = std::min(best, runs);
  } while (std::next_permutation(order.begin(), order.end()));
  return best;
}

void expect_consistent_report(const Rows& rows, const std::vector<uint32_t>& initial,
                              const std::vector<uint32_t>& order, const DiskOrderReport& report) {
  EXPECT_EQ(report.runs_original, runs_by_bits(rows, initial));
  EXPECT_EQ(report.runs_final, runs_by_bits(rows, order));
  EXPECT_LE(report.runs_final, report.runs_after_first_iteration);
  EXPECT_LE(report.runs_after_first_iteration, report.runs_after_seed);
}

TEST(DiskOrder, SmallMatricesNeverLoseToTheSeedTourAndOftenReachTheOptimum) {
  Random random(6);
  int optimal = 0, trials = 0;
  for (uint32_t columns = 1; columns <= 9; ++columns) {
    for (int trial = 0; trial < (columns == 9 ? 3 : 12); ++trial, ++trials) {
      const Rows rows = random_rows(random, uint32_t(random.integer(1, 20)), columns,
                                    0.2 + 0.5 * random.uniform());
      const SparseColumns m = columns_from_rows(rows, columns);
      DiskOrderOptions options;
      options.k = uint32_t(random.integer(2, 8));
      options.max_iterations = 200;
      options.seed = uint64_t(trial);
      const std::vector<uint32_t> initial = shuffled(random, columns);
      DiskOrderReport report;
      const std::vector<uint32_t> order = disk_order(m, initial, options, &report);
      ASSERT_TRUE(is_permutation_of(order, columns));
      expect_consistent_report(rows, initial, order, report);
      const uint64_t best = optimum_runs(rows, columns);
      EXPECT_GE(report.runs_final, best);
      optimal += report.runs_final == best;
    }
  }
  // A heuristic, but on matrices this small the kicks should find most optima.
  EXPECT_GE(optimal, trials * 3 / 4) << optimal << " optimal of " << trials;
}

// On a shuffled consecutive-ones matrix (one run per row in the hidden order) the heuristic
// comes close to one run per row, from many more in the shuffled order.
void expect_recovers_planted_order(bool use_sampling) {
  const uint32_t columns = 600, row_count = 1500;
  const PlantedMatrix p = planted_matrix(columns, row_count, 30, 0.0, 7);
  const SparseColumns m = columns_from_rows(p.rows, columns);
  ASSERT_EQ(total_runs(p.rows, p.hidden), row_count);
  DiskOrderOptions options;
  options.use_sampling = use_sampling;
  options.max_iterations = 3000;
  DiskOrderReport report;
  const std::vector<uint32_t> initial = identity_order(columns);
  const std::vector<uint32_t> order = disk_order(m, initial, options, &report);
  ASSERT_TRUE(is_permutation_of(order, columns));
  expect_consistent_report(p.rows, initial, order, report);
  EXPECT_GT(report.runs_original, 5 * row_count);
  EXPECT_LE(report.runs_final, row_count * 3 / 2);
  EXPECT_GE(report.improvement_final(), report.improvement_first());
}

TEST(DiskOrder, RecoversAPlantedConsecutiveOnesOrderWithExactLists) {
  expect_recovers_planted_order(false);
}

TEST(DiskOrder, RecoversAPlantedConsecutiveOnesOrderWithSampledLists) {
  expect_recovers_planted_order(true);
}

TEST(DiskOrder, AnInitialSeedTourIsOnlyImproved) {
  const PlantedMatrix p = planted_matrix(300, 700, 25, 0.2, 8);
  const SparseColumns m = columns_from_rows(p.rows, 300);
  DiskOrderOptions options;
  options.seed_tour = SeedTour::kInitial;
  options.max_iterations = 500;
  DiskOrderReport report;
  const std::vector<uint32_t> order = disk_order(m, p.hidden, options, &report);
  EXPECT_EQ(report.runs_after_seed, report.runs_original);
  expect_consistent_report(p.rows, p.hidden, order, report);
}

TEST(DiskOrder, TheSameSeedGivesTheSameOrderOnAnyThreadCount) {
  const PlantedMatrix p = planted_matrix(500, 1200, 25, 0.3, 9);
  const SparseColumns m = columns_from_rows(p.rows, 500);
  for (bool use_sampling : {false, true}) {
    DiskOrderOptions options;
    options.use_sampling = use_sampling;
    options.max_iterations = 1000;
    options.seed = 42;
    options.threads = 1;
    const std::vector<uint32_t> one = disk_order(m, identity_order(500), options);
    options.threads = 2;
    EXPECT_EQ(disk_order(m, identity_order(500), options), one);
    options.threads = 0;
    EXPECT_EQ(disk_order(m, identity_order(500), options), one);
  }
}

TEST(DiskOrder, DegenerateMatrices) {
  for (uint32_t columns : {0u, 1u, 2u, 3u, 9u}) {
    for (const Rows& rows : {Rows{}, Rows(4), Rows(2, identity_order(columns))}) {
      for (bool use_sampling : {false, true}) {
        const SparseColumns m = columns_from_rows(rows, columns);
        DiskOrderOptions options;
        options.use_sampling = use_sampling;
        DiskOrderReport report;
        const std::vector<uint32_t> order =
            disk_order(m, identity_order(columns), options, &report);
        ASSERT_TRUE(is_permutation_of(order, columns));
        expect_consistent_report(rows, identity_order(columns), order, report);
        EXPECT_EQ(nearest_neighbours(m, options).size(), columns);
      }
    }
  }
}

TEST(DiskOrder, RefusesABadInitialOrderOrMatrix) {
  const SparseColumns m = columns_from_rows({{0, 1}, {1, 2}}, 3);
  EXPECT_THROW(disk_order(m, std::vector<uint32_t>{0, 1}, {}), Error);
  EXPECT_THROW(disk_order(m, std::vector<uint32_t>{0, 2, 2}, {}), Error);
  SparseColumns unsorted = m;
  unsorted.columns[1] = {1, 0};
  EXPECT_THROW(disk_order(unsorted, identity_order(3), {}), Error);
  SparseColumns out_of_range = m;
  out_of_range.columns[0] = {2};
  EXPECT_THROW(disk_order(out_of_range, identity_order(3), {}), Error);
}

// The seed's Table 1 on planted matrices with noise, for exact and sampled lists: short rows
// (intervals of up to 60 columns, 4 rows per column, about the seed's 360000 × 27000 at the top)
// and long rows (up to 1000 columns, 1 row per 2 columns), where the exact lists' Σ |row|² grows.
// The Morton order against codes built bit by bit from the same 21-bit quantisation.
TEST(DiskOrder, MortonOrderSortsByInterleavedBits) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-50.0f, 250.0f);
  std::vector<std::array<float, 3>> points(500);
  for (auto& p : points) p = {u(rng), u(rng), std::floor(u(rng) / 50.0f)};  // z repeats: ties
  points.push_back(points[7]);                                               // an exact tie
  std::array<double, 3> lo{1e30, 1e30, 1e30}, hi{-1e30, -1e30, -1e30};
  for (const auto& p : points)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], double(p[a])), hi[a] = std::max(hi[a], double(p[a]));
  std::vector<std::pair<uint64_t, uint32_t>> expected;
  for (uint32_t i = 0; i < points.size(); ++i) {
    uint64_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const double cells = double(1 << 21);
      const auto q = uint64_t(std::min(cells - 1, std::floor((points[i][a] - lo[a]) / (hi[a] - lo[a]) * cells)));
      for (int bit = 0; bit < 21; ++bit) code |= ((q >> bit) & 1) << (3 * bit + a);
    }
    expected.push_back({code, i});
  }
  std::sort(expected.begin(), expected.end());
  const std::vector<uint32_t> order = morton_order(points);
  ASSERT_EQ(order.size(), points.size());
  for (size_t k = 0; k < order.size(); ++k) EXPECT_EQ(order[k], expected[k].second) << k;
  // The unit cube's corners, shuffled, come back in Z order: x fastest, then y, then z.
  const std::vector<std::array<float, 3>> corners{{1, 1, 1}, {0, 0, 0}, {1, 0, 1}, {0, 1, 0},
                                                  {1, 1, 0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 1}};
  EXPECT_EQ(morton_order(corners), (std::vector<uint32_t>{1, 6, 3, 4, 5, 2, 7, 0}));
  EXPECT_TRUE(morton_order(std::vector<std::array<float, 3>>{}).empty());
  EXPECT_EQ(morton_order(std::vector<std::array<float, 3>>{{3, 3, 3}, {3, 3, 3}}), (std::vector<uint32_t>{0, 1}));
}

}  // namespace
}  // namespace cellwalk::visibility
