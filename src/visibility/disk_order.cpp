// The disk order of the pieces by a Hamming-metric TSP: seed 001 vLOD §3 (digest §3.5, Table 1
// in §5).
//   F. Alizadeh, R. M. Karp, L. A. Newberg, D. K. Weisser. Physical mapping of chromosomes: a
//   combinatorial problem in molecular biology. 1993. (A tour through the columns and one
//   all-zero column has Hamming length 2·R(M): each run begins and ends with one differing bit.)
//   D. S. Johnson, L. A. McGeoch. The traveling salesman problem: a case study in local
//   optimization. 1997. (Neighbour lists, greedy seed, 2-opt/Or-opt with don't-look bits,
//   array tours reversing the shorter side, iterated local search with double-bridge kicks.)
#include "cellwalk/visibility/disk_order.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <numeric>
#include <string>
#include <tuple>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"

namespace cellwalk::visibility {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
// [ours] The kick swaps two adjacent segments of at most this many columns: a local double
// bridge, so a kick and its repair stay cheap however long the tour.
constexpr uint32_t kKickSegment = 50;

bool nearer(const Neighbour& a, const Neighbour& b) {
  return std::tie(a.distance, a.column) < std::tie(b.distance, b.column);
}

// Keeps the k nearest of `candidates`, ascending by (distance, column).
void keep_nearest(std::vector<Neighbour>& candidates, uint32_t k) {
  if (candidates.size() > k) {
    std::nth_element(candidates.begin(), candidates.begin() + k, candidates.end(), nearer);
    candidates.resize(k);
  }
  std::sort(candidates.begin(), candidates.end(), nearer);
}

// The matrix as the heuristic reads it: the caller's columns, optionally followed by one empty
// column (the all-zero column that closes the tour), with the rows for overlap queries and the
// columns by ascending (nnz, id): among columns that share no row with p, H(p, v) = |p| + |v|,
// so the first of that order are the nearest of them.
class Columns {
 public:
  Columns(const SparseColumns& matrix, bool with_empty)
      : matrix_(matrix),
        count_(uint32_t(matrix.columns.size()) + (with_empty ? 1 : 0)),
        rows_(matrix.rows) {
    for (uint32_t c = 0; c < matrix.columns.size(); ++c) {
      const std::vector<uint32_t>& column = matrix.columns[c];
      for (size_t i = 0; i < column.size(); ++i) {
        if (column[i] >= matrix.rows || (i > 0 && column[i] <= column[i - 1]))
          fail("disk order: column " + std::to_string(c),
               "row ids must be ascending and below the row count " + std::to_string(matrix.rows) +
                   "; build the matrix with columns_from_rows");
        rows_[column[i]].push_back(c);
      }
    }
    by_nnz_.resize(count_);
    std::iota(by_nnz_.begin(), by_nnz_.end(), 0u);
    std::stable_sort(by_nnz_.begin(), by_nnz_.end(),
                     [&](uint32_t a, uint32_t b) { return nnz(a) < nnz(b); });
  }

  uint32_t size() const { return count_; }
  std::span<const uint32_t> operator[](uint32_t c) const {
    return c < matrix_.columns.size() ? std::span<const uint32_t>(matrix_.columns[c])
                                      : std::span<const uint32_t>();
  }
  uint32_t nnz(uint32_t c) const { return uint32_t((*this)[c].size()); }
  uint32_t distance(uint32_t a, uint32_t b) const { return hamming((*this)[a], (*this)[b]); }
  uint32_t row_count() const { return uint32_t(rows_.size()); }
  const std::vector<uint32_t>& row(uint32_t r) const { return rows_[r]; }
  const std::vector<uint32_t>& by_nnz() const { return by_nnz_; }

 private:
  const SparseColumns& matrix_;
  uint32_t count_;
  std::vector<std::vector<uint32_t>> rows_;
  std::vector<uint32_t> by_nnz_;
};

// |p ∩ v| for one query column p and every other column v sharing a row with it (`touched`;
// count is 0 elsewhere). Scratch for one thread; clear() before the next query.
struct Overlaps {
  explicit Overlaps(uint32_t columns) : count(columns, 0) {}

  void gather(const Columns& columns, uint32_t p) {
    for (uint32_t r : columns[p])
      for (uint32_t v : columns.row(r))
        if (v != p && count[v]++ == 0) touched.push_back(v);
  }
  void clear() {
    for (uint32_t v : touched) count[v] = 0;
    touched.clear();
  }

  std::vector<uint32_t> count;
  std::vector<uint32_t> touched;
};

std::vector<Neighbour> exact_list(const Columns& columns, uint32_t p, uint32_t k, Overlaps& o) {
  o.gather(columns, p);
  std::vector<Neighbour> candidates;
  candidates.reserve(o.touched.size() + k);
  for (uint32_t v : o.touched)
    candidates.push_back({v, columns.nnz(p) + columns.nnz(v) - 2 * o.count[v]});
  uint32_t disjoint = 0;
  for (uint32_t v : columns.by_nnz()) {
    if (disjoint == k) break;
    if (v == p || o.count[v] != 0) continue;
    candidates.push_back({v, columns.nnz(p) + columns.nnz(v)});
    ++disjoint;
  }
  o.clear();
  keep_nearest(candidates, k);
  return candidates;
}

// Runs fill(p, scratch) for every column p on `threads` threads (0 = all), with one
// make_scratch() per block of columns.
template <class MakeScratch, class Fill>
void for_each_column(uint32_t count, uint32_t threads, MakeScratch make_scratch, Fill fill) {
  tbb::task_arena arena(threads == 0 ? tbb::task_arena::automatic : int(threads));
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, count, 256), [&](const auto& block) {
      auto scratch = make_scratch();
      for (uint32_t p = block.begin(); p != block.end(); ++p) fill(p, scratch);
    });
  });
}

NeighbourLists exact_lists(const Columns& columns, uint32_t k, uint32_t threads) {
  NeighbourLists lists(columns.size());
  for_each_column(
      columns.size(), threads, [&] { return Overlaps(columns.size()); },
      [&](uint32_t p, Overlaps& o) { lists[p] = exact_list(columns, p, k, o); });
  return lists;
}

// The single random sample of the seed's near-neighbour trick, with each row's sample members
// so that a column's distances to all of them cost Σ_{r ∈ p} |row r ∩ sample|.
class Sample {
 public:
  Sample(const Columns& columns, const DiskOrderOptions& options) : columns_(columns) {
    const uint32_t n = columns.size();
    const double wanted = std::ceil(options.sample_factor * std::log(double(std::max(n, 2u))));
    const uint32_t size = uint32_t(std::min(double(n), std::max(1.0, wanted)));
    std::vector<uint32_t> pool(n);
    std::iota(pool.begin(), pool.end(), 0u);
    Random random(options.seed);
    for (uint32_t i = 0; i < size; ++i)  // a partial Fisher-Yates shuffle
      std::swap(pool[i], pool[i + uint32_t(random.integer(0, n - 1 - i))]);
    members_.assign(pool.begin(), pool.begin() + size);
    std::sort(members_.begin(), members_.end());
    row_members_.resize(columns.row_count());
    for (uint32_t i = 0; i < size; ++i)
      for (uint32_t r : columns[members_[i]]) row_members_[r].push_back(i);
  }

  uint32_t size() const { return uint32_t(members_.size()); }
  uint32_t member(uint32_t i) const { return members_[i]; }
  // out[i] = H(p, member(i)).
  void distances(uint32_t p, std::vector<uint32_t>& out) const {
    out.assign(members_.size(), 0);
    for (uint32_t r : columns_[p])
      for (uint32_t i : row_members_[r]) ++out[i];
    for (uint32_t i = 0; i < out.size(); ++i)
      out[i] = columns_.nnz(p) + columns_.nnz(members_[i]) - 2 * out[i];
  }

 private:
  const Columns& columns_;
  std::vector<uint32_t> members_;                   // ascending column ids
  std::vector<std::vector<uint32_t>> row_members_;  // per row, the sample ordinals with a 1 there
};

// The groups of the sampled lists: each sample member's columns (those nearest to it, the seed's
// 2-approximate nearest neighbour), nearest to it first.
struct SampleGroups {
  std::vector<std::vector<uint32_t>> members;  // by sample ordinal
  std::vector<bool> in_sample;                 // by column
};

SampleGroups sample_groups(const Columns& columns, const Sample& sample, uint32_t threads) {
  std::vector<std::pair<uint32_t, uint32_t>> nearest(columns.size());  // (distance, ordinal)
  for_each_column(
      columns.size(), threads, [] { return std::vector<uint32_t>(); },
      [&](uint32_t p, std::vector<uint32_t>& distances) {
        sample.distances(p, distances);
        nearest[p] = {kNone, kNone};
        for (uint32_t i = 0; i < sample.size(); ++i)
          nearest[p] = std::min(nearest[p], std::pair(distances[i], i));
      });
  std::vector<uint32_t> by_nearness = identity_order(columns.size());
  std::sort(by_nearness.begin(), by_nearness.end(), [&](uint32_t a, uint32_t b) {
    return std::tie(nearest[a].first, a) < std::tie(nearest[b].first, b);
  });
  SampleGroups groups{std::vector<std::vector<uint32_t>>(sample.size()),
                      std::vector<bool>(columns.size(), false)};
  for (uint32_t c : by_nearness) groups.members[nearest[c].second].push_back(c);
  for (uint32_t i = 0; i < sample.size(); ++i) groups.in_sample[sample.member(i)] = true;
  return groups;
}

// p's candidates: every sample member, then the groups of the members nearest to p until
// `options.candidates` more; the k nearest of them.
std::vector<Neighbour> sampled_list(const Columns& columns, const Sample& sample,
                                    const SampleGroups& groups, uint32_t p,
                                    const DiskOrderOptions& options,
                                    std::vector<uint32_t>& distances) {
  sample.distances(p, distances);
  std::vector<Neighbour> candidates;
  std::vector<std::pair<uint32_t, uint32_t>> pivots;  // (distance, ordinal): ordinals ascend as ids
  for (uint32_t i = 0; i < sample.size(); ++i) {
    if (sample.member(i) != p) candidates.push_back({sample.member(i), distances[i]});
    pivots.emplace_back(distances[i], i);
  }
  // Few pivots are probed: sort a head, and the rest only when the head runs out.
  const size_t head = std::min<size_t>(pivots.size(), 16);
  std::partial_sort(pivots.begin(), pivots.begin() + head, pivots.end());
  const size_t wanted = candidates.size() + options.candidates;
  for (size_t j = 0; j < pivots.size() && candidates.size() < wanted; ++j) {
    if (j == head) std::sort(pivots.begin() + head, pivots.end());
    for (uint32_t v : groups.members[pivots[j].second]) {
      if (candidates.size() == wanted) break;
      if (v != p && !groups.in_sample[v]) candidates.push_back({v, columns.distance(p, v)});
    }
  }
  keep_nearest(candidates, options.k);
  return candidates;
}

NeighbourLists sampled_lists(const Columns& columns, const DiskOrderOptions& options) {
  const Sample sample(columns, options);
  const SampleGroups groups = sample_groups(columns, sample, options.threads);
  NeighbourLists lists(columns.size());
  for_each_column(
      columns.size(), options.threads, [] { return std::vector<uint32_t>(); },
      [&](uint32_t p, std::vector<uint32_t>& distances) {
        lists[p] = sampled_list(columns, sample, groups, p, options, distances);
      });
  return lists;
}

NeighbourLists lists_for(const Columns& columns, const DiskOrderOptions& options) {
  return options.use_sampling ? sampled_lists(columns, options)
                              : exact_lists(columns, options.k, options.threads);
}

// The nearest unvisited column to p by (distance, id), over all columns: the seed's full query
// when p's list is exhausted. `cursor` only advances: by_nnz before it are all visited.
uint32_t nearest_unvisited(const Columns& columns, uint32_t p, const std::vector<bool>& visited,
                           Overlaps& o, size_t& cursor) {
  o.gather(columns, p);
  Neighbour best{kNone, kNone};
  const auto consider = [&](Neighbour n) {
    if (nearer(n, best)) best = n;
  };
  for (uint32_t v : o.touched)
    if (!visited[v]) consider({v, columns.nnz(p) + columns.nnz(v) - 2 * o.count[v]});
  const std::vector<uint32_t>& by_nnz = columns.by_nnz();
  while (cursor < by_nnz.size() && visited[by_nnz[cursor]]) ++cursor;
  for (size_t i = cursor; i < by_nnz.size(); ++i) {
    const uint32_t v = by_nnz[i];
    if (visited[v] || o.count[v] != 0) continue;
    consider({v, columns.nnz(p) + columns.nnz(v)});
    break;
  }
  o.clear();
  return best.column;
}

// The seed's greedy tour: from `start`, always to the nearest unvisited column of the current
// one's list, or of all columns when the list holds none.
std::vector<uint32_t> greedy_tour(const Columns& columns, const NeighbourLists& lists,
                                  uint32_t start) {
  std::vector<bool> visited(columns.size(), false);
  std::vector<uint32_t> tour;
  tour.reserve(columns.size());
  Overlaps o(columns.size());
  size_t cursor = 0;
  for (uint32_t current = start; current != kNone;) {
    visited[current] = true;
    tour.push_back(current);
    if (tour.size() == columns.size()) break;
    uint32_t next = kNone;
    for (const Neighbour& n : lists[current]) {
      if (!visited[n.column]) {
        next = n.column;
        break;
      }
    }
    current = next != kNone ? next : nearest_unvisited(columns, current, visited, o, cursor);
  }
  return tour;
}

// Σ of H over the consecutive columns of a cyclic tour.
int64_t tour_length(const Columns& columns, const std::vector<uint32_t>& tour) {
  int64_t length = 0;
  for (size_t i = 0; i < tour.size(); ++i)
    length += columns.distance(tour[i], tour[(i + 1) % tour.size()]);
  return length;
}

// R(M) of an order of the caller's columns: half the length of the tour closed by the empty
// column (AKNW93).
uint64_t runs_of(const Columns& columns, std::span<const uint32_t> order) {
  if (order.empty()) return 0;
  uint64_t length = columns.nnz(order.front()) + columns.nnz(order.back());
  for (size_t i = 0; i + 1 < order.size(); ++i) length += columns.distance(order[i], order[i + 1]);
  return length / 2;
}

// A cyclic tour as an array and its inverse ([JM97]): next and prev in O(1), a 2-opt move
// reverses the shorter of the two paths it may reverse. While a trial is open every reversal is
// journalled, so the trial can be undone exactly.
class Tour {
 public:
  explicit Tour(std::vector<uint32_t> nodes) : node_(std::move(nodes)), pos_(node_.size()) {
    for (uint32_t i = 0; i < node_.size(); ++i) pos_[node_[i]] = i;
  }

  uint32_t size() const { return uint32_t(node_.size()); }
  uint32_t at(uint32_t position) const { return node_[position]; }
  uint32_t next(uint32_t v) const { return node_[pos_[v] + 1 == size() ? 0 : pos_[v] + 1]; }
  uint32_t prev(uint32_t v) const { return node_[pos_[v] == 0 ? size() - 1 : pos_[v] - 1]; }
  uint32_t step(uint32_t v, bool forward) const { return forward ? next(v) : prev(v); }
  const std::vector<uint32_t>& nodes() const { return node_; }

  // Replaces the edges (a, b), (c, d) by (a, c), (b, d).
  // REQUIRES: b = next(a) and d = next(c), or b = prev(a) and d = prev(c).
  void two_opt(uint32_t a, uint32_t b, uint32_t c, [[maybe_unused]] uint32_t d) {
    assert((next(a) == b && next(c) == d) || (prev(a) == b && prev(c) == d));
    if (next(a) == b)
      reverse(b, c);
    else
      reverse(c, b);
  }

  // Moves the path x..y (forward) between the adjacent u and w = next(u), both outside it:
  // u x..y w, or u y..x w when `reversed`. Two or three 2-opt moves.
  void move_segment(uint32_t x, uint32_t y, uint32_t u, uint32_t w, bool reversed) {
    const uint32_t p = prev(x), n = next(y);
    two_opt(p, x, u, w);  // p u..n y..x w
    two_opt(p, u, n, y);  // p n..u y..x w
    if (!reversed) two_opt(u, y, x, w);
  }

  void begin_trial() {
    journal_.clear();
    journaling_ = true;
  }
  void keep_trial() { journaling_ = false; }
  void undo_trial() {
    for (auto it = journal_.rbegin(); it != journal_.rend(); ++it)
      reverse_positions(it->first, it->second);
    journaling_ = false;
  }

 private:
  // Reverses the path from..to (forward), or the rest of the cycle when that is shorter: the
  // same tour as a cycle.
  void reverse(uint32_t from, uint32_t to) {
    uint32_t first = pos_[from];
    uint32_t length = (pos_[to] + size() - first) % size() + 1;
    if (2 * length > size()) {
      first = (pos_[to] + 1) % size();
      length = size() - length;
    }
    reverse_positions(first, length);
    if (journaling_) journal_.emplace_back(first, length);
  }
  // Reverses the `length` positions from `first` on, cyclically: its own inverse.
  void reverse_positions(uint32_t first, uint32_t length) {
    if (length < 2) return;
    uint32_t i = first, j = (first + length - 1) % size();
    for (uint32_t s = 0; s < length / 2; ++s) {
      std::swap(node_[i], node_[j]);
      pos_[node_[i]] = i;
      pos_[node_[j]] = j;
      i = i + 1 == size() ? 0 : i + 1;
      j = j == 0 ? size() - 1 : j - 1;
    }
  }

  std::vector<uint32_t> node_, pos_;
  std::vector<std::pair<uint32_t, uint32_t>> journal_;  // (first, length) of each reversal
  bool journaling_ = false;
};

// 2-opt and Or-opt (segments of 1 to 3 columns, either way round) restricted to the neighbour
// lists, first improvement, with a queue of nodes whose surroundings changed (JM97's don't-look
// bits). Tracks the tour length through the gains.
class LocalSearch {
 public:
  LocalSearch(const Columns& columns, const NeighbourLists& lists, Tour& tour)
      : columns_(columns),
        lists_(lists),
        tour_(tour),
        queued_(tour.size(), false),
        length_(tour_length(columns, tour.nodes())) {}

  int64_t length() const { return length_; }
  void set_length(int64_t length) { length_ = length; }
  void add_length(int64_t delta) { length_ += delta; }

  void activate(uint32_t v) {
    if (!queued_[v]) {
      queued_[v] = true;
      queue_.push_back(v);
    }
  }
  // Until no queued node has an improving move.
  void run() {
    while (!queue_.empty()) {
      const uint32_t v = queue_.front();
      queue_.pop_front();
      queued_[v] = false;
      if (improve_two_opt(v) || improve_or_opt(v)) activate(v);
    }
    assert(length_ == tour_length(columns_, tour_.nodes()));
  }

 private:
  uint32_t d(uint32_t a, uint32_t b) const { return columns_.distance(a, b); }

  void apply(int64_t gain, std::initializer_list<uint32_t> touched) {
    length_ -= gain;
    for (uint32_t v : touched) activate(v);
  }

  // Replaces (a, b) and (c, d), b and d a's and c's neighbours on the same side, by (a, c)
  // and (b, d), for c in a's list nearer to a than b is.
  bool improve_two_opt(uint32_t a) {
    for (bool forward : {true, false}) {
      const uint32_t b = tour_.step(a, forward);
      const int64_t removed = d(a, b);
      for (const Neighbour& n : lists_[a]) {
        if (n.distance >= removed) break;
        const uint32_t c = n.column, e = tour_.step(c, forward);
        if (c == b || e == a) continue;
        const int64_t gain = removed + d(c, e) - n.distance - d(b, e);
        if (gain > 0) {
          tour_.two_opt(a, b, c, e);
          apply(gain, {a, b, c, e});
          return true;
        }
      }
    }
    return false;
  }

  // Moves the segment s..e (1 to 3 columns from s, either way) out from between its outer
  // neighbours ps and ne, next to a column c of s's list: c s..e d for d a tour neighbour of c.
  bool improve_or_opt(uint32_t s) {
    for (bool forward : {true, false}) {
      uint32_t segment[3] = {s, s, s};
      for (uint32_t last = 0; last < 3; ++last) {
        const uint32_t length = last + 1;
        if (tour_.size() < length + 3) break;
        if (last > 0) segment[last] = tour_.step(segment[last - 1], forward);
        if (last == 0 && !forward) continue;  // the same moves as forward
        const uint32_t e = segment[last];
        const uint32_t ps = tour_.step(s, !forward), ne = tour_.step(e, forward);
        const int64_t opened = int64_t(d(ps, s)) + d(e, ne) - d(ps, ne);
        if (opened <= 0) continue;
        const auto inside = [&](uint32_t v) {
          return std::find(segment, segment + length, v) != segment + length;
        };
        for (const Neighbour& n : lists_[s]) {
          if (n.distance >= opened) break;
          const uint32_t c = n.column;
          if (inside(c)) continue;
          for (bool side : {true, false}) {
            const uint32_t dn = tour_.step(c, side);
            if (inside(dn) || (c == ps && dn == ne) || (c == ne && dn == ps)) continue;
            const int64_t gain = opened + d(c, dn) - n.distance - d(dn, e);
            if (gain > 0) {
              move(s, e, forward, c, dn);
              apply(gain, {ps, ne, s, e, c, dn});
              return true;
            }
          }
        }
      }
    }
    return false;
  }

  // The segment s..e (forward from s when `forward`) between c and dn, with c next to s.
  void move(uint32_t s, uint32_t e, bool forward, uint32_t c, uint32_t dn) {
    const uint32_t x = forward ? s : e, y = forward ? e : s;
    const bool c_first = tour_.next(c) == dn;
    const uint32_t u = c_first ? c : dn, w = c_first ? dn : c;
    tour_.move_segment(x, y, u, w, c_first != (x == s));
  }

  const Columns& columns_;
  const NeighbourLists& lists_;
  Tour& tour_;
  std::deque<uint32_t> queue_;
  std::vector<bool> queued_;
  int64_t length_;
};

// Swaps two random adjacent segments of 1 to kKickSegment columns (p X Y w → p Y X w: a double
// bridge confined to a window) and queues the six columns at the changed edges.
void kick(Tour& tour, LocalSearch& search, const Columns& columns, Random& random) {
  const uint32_t longest = std::min(kKickSegment, (tour.size() - 2) / 2);
  const uint32_t x = tour.at(uint32_t(random.integer(0, tour.size() - 1)));
  uint32_t y = x;
  for (int64_t i = random.integer(1, longest); i > 1; --i) y = tour.next(y);
  const uint32_t p = tour.prev(x), n = tour.next(y);
  uint32_t u = n;
  for (int64_t i = random.integer(1, longest); i > 1; --i) u = tour.next(u);
  const uint32_t w = tour.next(u);
  const auto d = [&](uint32_t a, uint32_t b) { return int64_t(columns.distance(a, b)); };
  search.add_length(d(p, n) + d(u, x) + d(y, w) - d(p, x) - d(y, n) - d(u, w));
  tour.move_segment(x, y, u, w, false);  // p n..u x..y w
  for (uint32_t v : {p, x, y, n, u, w}) search.activate(v);
}

void require_permutation(std::span<const uint32_t> order, size_t columns, const char* where) {
  std::vector<bool> seen(columns, false);
  bool ok = order.size() == columns;
  for (size_t i = 0; ok && i < order.size(); ++i) {
    ok = order[i] < columns && !seen[order[i]];
    if (ok) seen[order[i]] = true;
  }
  if (!ok)
    fail(where, "the order must hold each of the " + std::to_string(columns) +
                    " column ids exactly once (identity_order gives one)");
}

}  // namespace

SparseColumns columns_from_rows(const std::vector<std::vector<uint32_t>>& rows,
                                uint32_t column_count) {
  SparseColumns m{uint32_t(rows.size()), std::vector<std::vector<uint32_t>>(column_count)};
  for (uint32_t r = 0; r < rows.size(); ++r) {
    for (size_t i = 0; i < rows[r].size(); ++i) {
      const uint32_t c = rows[r][i];
      if (c >= column_count || (i > 0 && c <= rows[r][i - 1]))
        fail("disk order: row " + std::to_string(r),
             "column ids must be ascending and below the column count " +
                 std::to_string(column_count));
      m.columns[c].push_back(r);
    }
  }
  return m;
}

uint64_t total_runs(const std::vector<std::vector<uint32_t>>& rows,
                    std::span<const uint32_t> order) {
  require_permutation(order, order.size(), "total_runs");
  std::vector<uint32_t> position(order.size());
  for (uint32_t k = 0; k < order.size(); ++k) position[order[k]] = k;
  uint64_t runs = 0;
  std::vector<uint32_t> positions;
  for (uint32_t r = 0; r < rows.size(); ++r) {
    positions.clear();
    for (uint32_t c : rows[r]) {
      if (c >= order.size())
        fail("total_runs: row " + std::to_string(r) + ", column " + std::to_string(c),
             "the order holds only " + std::to_string(order.size()) + " columns");
      positions.push_back(position[c]);
    }
    std::sort(positions.begin(), positions.end());
    for (size_t i = 0; i < positions.size(); ++i)
      runs += i == 0 || positions[i] != positions[i - 1] + 1;
  }
  return runs;
}

uint32_t hamming(std::span<const uint32_t> u, std::span<const uint32_t> v) {
  size_t i = 0, j = 0, common = 0;
  while (i < u.size() && j < v.size()) {
    if (u[i] < v[j]) {
      ++i;
    } else if (v[j] < u[i]) {
      ++j;
    } else {
      ++common;
      ++i;
      ++j;
    }
  }
  return uint32_t(u.size() + v.size() - 2 * common);
}

std::vector<uint32_t> identity_order(uint32_t n) {
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  return order;
}

namespace {

// The 21 low bits of v spread to every third bit (bit i to bit 3i).
uint64_t spread_bits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

}  // namespace

std::vector<uint32_t> morton_order(std::span<const std::array<float, 3>> points) {
  std::array<float, 3> lo{}, hi{};
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<float>::max();
    hi[a] = std::numeric_limits<float>::lowest();
  }
  for (const auto& p : points)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  constexpr double kCells = double(1 << 21);
  std::vector<uint64_t> code(points.size(), 0);
  for (size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      const double extent = double(hi[a]) - double(lo[a]);
      const double t = extent > 0 ? (double(points[i][a]) - double(lo[a])) / extent : 0.0;
      code[i] |= spread_bits(uint64_t(std::min(kCells - 1, std::floor(t * kCells)))) << a;
    }
  std::vector<uint32_t> order = identity_order(uint32_t(points.size()));
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return code[a] < code[b]; });
  return order;
}

NeighbourLists nearest_neighbours(const SparseColumns& matrix, const DiskOrderOptions& options) {
  return lists_for(Columns(matrix, false), options);
}

std::vector<uint32_t> disk_order(const SparseColumns& matrix, std::span<const uint32_t> initial,
                                 const DiskOrderOptions& options, DiskOrderReport* report) {
  const uint32_t n = uint32_t(matrix.columns.size());
  require_permutation(initial, n, "disk_order: initial order");
  DiskOrderReport r;
  const Columns columns(matrix, true);  // column n is the empty one that closes the tour
  r.runs_original = runs_of(columns, initial);

  Clock::time_point start = Clock::now();
  const NeighbourLists lists = lists_for(columns, options);
  r.knn_seconds = seconds_since(start);

  start = Clock::now();
  std::vector<uint32_t> seed;
  if (options.seed_tour == SeedTour::kGreedy) {
    seed = greedy_tour(columns, lists, n);
  } else {
    seed.push_back(n);
    seed.insert(seed.end(), initial.begin(), initial.end());
  }
  Tour tour(std::move(seed));
  r.seed_tour_seconds = seconds_since(start);
  LocalSearch search(columns, lists, tour);
  r.runs_after_seed = uint64_t(search.length() / 2);

  start = Clock::now();
  if (options.max_iterations > 0) {
    for (uint32_t v : tour.nodes()) search.activate(v);
    search.run();
    r.iterations = 1;
  }
  r.first_iteration_seconds = seconds_since(start);
  r.runs_after_first_iteration = uint64_t(search.length() / 2);

  start = Clock::now();
  Random random(options.seed ^ 0x6B69636Bull);  // "kick": apart from the sample's stream
  for (; tour.size() >= 8 && r.iterations < options.max_iterations; ++r.iterations) {
    if (seconds_since(start) > options.max_seconds) break;
    const int64_t before = search.length();
    tour.begin_trial();
    kick(tour, search, columns, random);
    search.run();
    if (search.length() <= before) {
      tour.keep_trial();
    } else {
      tour.undo_trial();
      search.set_length(before);
    }
  }
  r.later_iterations_seconds = seconds_since(start);

  // The order is the tour read from the empty column on.
  const std::vector<uint32_t>& cycle = tour.nodes();
  const auto empty = std::find(cycle.begin(), cycle.end(), n);
  std::vector<uint32_t> order(empty + 1, cycle.end());
  order.insert(order.end(), cycle.begin(), empty);
  r.runs_final = runs_of(columns, order);
  if (report) *report = r;
  return order;
}

}  // namespace cellwalk::visibility
