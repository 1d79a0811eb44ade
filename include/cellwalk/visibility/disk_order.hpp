// The disk order of the pieces: a column permutation of the Δ matrix (rows = cell transitions,
// columns = pieces, a 1 where the Δ adds the piece) that makes each row few runs of consecutive
// columns, so that a Δ is few contiguous reads.
// Seed: 001 vLOD §3 (digest §3.5, Table 1 in §5): total runs R(M) as the objective; a tour over
// the columns under the Hamming distance with one all-zero column added is 2·R(M) [AKNW93];
// the [JM97] heuristic: k-NN lists (k = 20), a greedy nearest-unvisited-neighbour seed tour, then
// iterated 2-opt and Or-opt restricted to the lists.
//   [AKNW93] F. Alizadeh, R. M. Karp, L. A. Newberg, D. K. Weisser. Physical mapping of
//   chromosomes: a combinatorial problem in molecular biology. 1993.
//   [JM97] D. S. Johnson, L. A. McGeoch. The traveling salesman problem: a case study in local
//   optimization. 1997.
// Plain data in and out: no geometry, no GL; a caller builds the rows from its Δs and applies
// the order to its own files.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace cellwalk::visibility {

// A sparse binary matrix by column: columns[c] holds the ascending ids (< rows) of the rows with
// a 1 in column c.
struct SparseColumns {
  uint32_t rows = 0;
  std::vector<std::vector<uint32_t>> columns;
};

// The same matrix by column, from its rows (rows[r] = the ascending column ids of row r).
// Throws Error naming the row when a row is not strictly ascending or names a column
// >= column_count.
SparseColumns columns_from_rows(const std::vector<std::vector<uint32_t>>& rows,
                                uint32_t column_count);

// R(M) after permuting the columns by `order` (order[k] = the column placed at position k): over
// all rows, the number of maximal blocks of 1s at consecutive positions. R(0011100111010) = 3.
// Throws Error when `order` is not a permutation of 0..order.size()-1 or a row names a column
// outside it.
uint64_t total_runs(const std::vector<std::vector<uint32_t>>& rows,
                    std::span<const uint32_t> order);

// The Hamming distance of two columns given as ascending row ids: the size of their symmetric
// difference, in O(|u| + |v|).
uint32_t hamming(std::span<const uint32_t> u, std::span<const uint32_t> v);

// 0, 1, ..., n-1: the order the pieces already have.
std::vector<uint32_t> identity_order(uint32_t n);

// The baseline of §3's comparison: the points' indices along the Morton (Z-order) curve over
// their bounding box, 21 bits an axis (x the lowest bit of each triple), ties by the smaller
// index. A box of zero extent on an axis puts every point at 0 on it.
std::vector<uint32_t> morton_order(std::span<const std::array<float, 3>> points);

// Where the improvement starts: the greedy tour of the seed, or the caller's order (e.g. a
// Morton order, to polish it instead).
enum class SeedTour { kGreedy, kInitial };

struct DiskOrderOptions {
  uint32_t k = 20;  // the length of each column's candidate list (seed: 20)
  // Exact lists (every column sharing a row, plus the sparsest of the rest, which are the nearest
  // among the others); with sampling, the candidates come from one random sample of columns
  // (seed's near-neighbour trick, see nearest_neighbours).
  bool use_sampling = false;
  double sample_factor = 100;  // c/α: the sample holds ceil(sample_factor · ln n) columns
  uint32_t candidates = 80;    // with sampling: at least this many candidates per column
  SeedTour seed_tour = SeedTour::kGreedy;
  // Improvement iterations: the first is a full 2-opt/Or-opt local search from the seed tour,
  // each later one a random segment swap (a local double bridge, [JM97]) followed by local
  // search, kept unless it adds runs. 0 returns the seed tour.
  uint32_t max_iterations = 20000;
  // A wall-clock bound on the iterations after the first; the result depends on the machine
  // only when it binds.
  double max_seconds = 60;
  uint64_t seed = 1;     // the sample and the kicks; the same seed gives the same order
  uint32_t threads = 0;  // for the lists; 0 = all cores. The lists do not depend on it
};

// What Table 1 of the seed reports, for one run of disk_order.
struct DiskOrderReport {
  double knn_seconds = 0;
  double seed_tour_seconds = 0;
  double first_iteration_seconds = 0;   // the local search from the seed tour
  double later_iterations_seconds = 0;  // all kicks and their local searches
  uint64_t runs_original = 0;           // R(M) in the caller's initial order
  uint64_t runs_after_seed = 0;
  uint64_t runs_after_first_iteration = 0;
  uint64_t runs_final = 0;
  uint32_t iterations = 0;  // including the first

  double seconds_per_later_iteration() const {
    return iterations > 1 ? later_iterations_seconds / (iterations - 1) : 0;
  }
  // Imp1 and Imp_many of Table 1: the original runs over the runs after the first iteration
  // and after the last.
  double improvement_first() const { return ratio(runs_original, runs_after_first_iteration); }
  double improvement_final() const { return ratio(runs_original, runs_final); }

 private:
  static double ratio(uint64_t a, uint64_t b) { return b == 0 ? 1.0 : double(a) / double(b); }
};

struct Neighbour {
  uint32_t column;
  uint32_t distance;  // Hamming
};
// neighbours[c]: up to k other columns, ascending by (distance, column id).
using NeighbourLists = std::vector<std::vector<Neighbour>>;

// Each column's k nearest other columns under the Hamming distance.
// Exact (use_sampling false): the true k nearest, ties by the smaller id; costs
// O(Σ_rows |row|² + Σ_columns |touched|).
// Sampled [ours, the seed gives no details]: one random sample Q of ceil(sample_factor · ln n)
// columns serves all columns (the seed: a sample of size c·log n/α hits the ball of radius 2·r_p
// of every p w.h.p. when that ball holds a fraction α of the points). Every column is assigned to
// its nearest sample column (a 2-approximate nearest neighbour); the candidates of p are Q and the
// members of the groups of p's nearest sample columns, taken in order until there are
// `candidates` of them. The lists are then the k nearest candidates.
NeighbourLists nearest_neighbours(const SparseColumns& matrix, const DiskOrderOptions& options);

// The column order of least total runs the heuristic finds, starting from `initial` (a
// permutation of the columns; its runs are report->runs_original). The result has
// runs_final <= runs_after_first_iteration <= runs_after_seed. Fills *report when given.
// Throws Error when `initial` is not a permutation of the matrix's columns.
std::vector<uint32_t> disk_order(const SparseColumns& matrix, std::span<const uint32_t> initial,
                                 const DiskOrderOptions& options,
                                 DiskOrderReport* report = nullptr);

}  // namespace cellwalk::visibility
