// The simulation of Zheng's §7.5 (seed 004; digest §5, "PVS simulation"): a city of square
// buildings whose streets are split into square view cells, a synthetic PVS table with the
// thesis's statistics (each cell sees about 5 % of the objects, adjacent cells share about 60 %),
// its two 3,000-step routes (one random with many back-and-forth crossings, one of 7 straight
// pieces joined by 6 right-angle turns), and a walk of each with SNP or PBNP over the same
// 9-entry cache, counting Table 7.2's transactions, cache swaps and objects sent.
#pragma once

#include <cstdint>
#include <vector>

#include "cellwalk/systems/pvs_stream/pvs_cache.hpp"
#include "cellwalk/systems/pvs_stream/pvs_prefetch.hpp"

namespace cellwalk::pvs_stream {

struct SyntheticCityParams {
  int blocks = 30;            // buildings along each side (the thesis: 30 × 30 = 900)
  double building = 100.0;    // m, the side of a building's base
  double street = 60.0;       // m, the width of a street (one street also runs round the city)
  double cell = 20.0;         // m, the side of a view cell
  double visible = 0.05;      // the fraction of the objects a cell sees
  // Each object is seen from rectangles of cells blob_min..blob_max cells on a side, centred
  // about its building (a normal spread of `spread` m): their edges set the adjacent overlap.
  int blob_min = 2, blob_max = 3;
  double spread = 900.0;
  uint64_t seed = 1;
};

struct SyntheticCity {
  SyntheticCityParams params;
  ViewcellGrid grid;
  PvsTable table;  // one object per building
  // Measured on the table: the mean |S_i| / objects over the view cells, and the mean
  // |S_i ∩ S_j| / |S_i| over ordered pairs of adjacent view cells.
  double visible_fraction = 0.0, adjacent_overlap = 0.0;
};

// REQUIRES: blocks >= 2; building and street multiples of cell (throws otherwise).
SyntheticCity make_synthetic_city(const SyntheticCityParams& params);

struct Point2 {
  double x = 0.0, z = 0.0;
};

struct RouteParams {
  int steps = 3000;
  double step = 4.0;           // m
  double reverse_chance = 0.05;  // route 1: a step turns back with this chance
  double turn_chance = 0.5;      // route 1: at a crossing, the walk turns with this chance
  uint64_t seed = 1;
};

// Route 1: a random walk along the streets (positions steps + 1, every one in a view cell).
std::vector<Point2> random_route(const SyntheticCity& city, const RouteParams& params);
// Route 2: seven straight pieces along street centre lines joined by six right turns (a spiral
// inwards), cut to `steps` steps.
std::vector<Point2> straight_route(const SyntheticCity& city, const RouteParams& params);

struct SimulationResult {
  uint64_t transactions = 0;    // prefetching transactions that fetched a row
  uint64_t cache_swaps = 0;     // rows brought into the cache (Table 7.2's "cache swaps")
  uint64_t evictions = 0;       // rows replaced
  uint64_t objects_sent = 0;    // Σ |ΔS|
  uint64_t first_prefetch = 0;  // |ΔS| of the first transaction
  uint64_t peak_objects = 0;    // most objects held at once
  uint64_t border_checks = 0;   // cell (SNP) or region (PBNP) crossings that were checked
  std::vector<uint32_t> objects_per_step;  // |ΔS| at each position (Figures 7.7, 7.8)
  double objects_per_transaction() const { return transactions ? double(objects_sent) / double(transactions) : 0.0; }
};

// Walks `route` with `algorithm`: at the first position and at each crossing of a cell border
// (SNP) or region border (PBNP, regions `band` × cell wide), the prefetching area is made cached.
// Also checks, at every position, that the database is the union of the cached rows and holds
// the current cell's row (throws otherwise: a broken cache, not a figure).
SimulationResult simulate(const SyntheticCity& city, const std::vector<Point2>& route, PrefetchAlgorithm algorithm,
                          double band = 0.25, size_t entries = 9);

}  // namespace cellwalk::pvs_stream
