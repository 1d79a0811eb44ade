// `cellwalk bench visibility` (issue 4): the visibility engines measured side by side in one
// run on generated worlds (DESIGN.md "Measuring": ratios, absolute times vary):
//   engines   cells per second (one thread), recall and tightness of sampling, conservative
//             and dov against rendered ground truth, on 2D grid cells at eye height of the
//             generated city and plant at ~10^6 triangles (and ~10^7 with --large);
//   refine    the conservative engine at each refinement level (0 = no refinement), same cells;
//   storage   the conservative sets of a block of neighbouring cells, gap-coded, stored (the
//             smallest of gaps, Δ from a neighbour or bitmask, as `cellwalk pvs` writes them) and
//             as plain bitmasks;
//   target    conservative sets for a block of cells on `threads` threads, cells per second, and
//             the time for 4,096 cells: measured on a 64 × 64 block of the 10^7-triangle city
//             with --large, else extrapolated from the storage block (the target:
//             < 10 min on 2 cores for a 10^7-triangle city).
// Writes <out>/visibility.md and <out>/visibility/{engines,refine,storage,target}.csv,
// tightness.svg.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cellwalk {

struct VisibilityBenchParams {
  uint64_t city_objects = 560;  // ~10^6 triangles (1,790 per object on average)
  int plant_units = 4;          // 4 × 4 units at detail 2: ~0.96 M triangles
  double plant_detail = 2.0;
  bool large = false;                 // also the ~10^7-triangle city and plant
  uint64_t large_city_objects = 5600;
  int large_plant_units = 13;         // 13 × 13 units at detail 2: ~10 M triangles
  float cell_size = 10.0f;            // grid cells at eye height (metres)
  int checked_cells = 12;             // cells checked against ground truth per world
  int dov_cells = 2;                  // of those, checked with the (slow) dov engine
  int truth_points = 8;               // random points per cell besides the 8 corners
  int truth_resolution = 512;         // cube-map face resolution of the ground truth
  std::vector<int> refine_levels = {0, 1, 2, 3};
  int storage_side = 8;               // a storage_side² block of neighbouring cells
  int large_target_side = 64;         // with --large, the 10^7 city's target block: 64² = 4,096 cells, measured
  int threads = 2;
  std::string out_dir = "docs/results";
  std::string work_dir;      // empty = a temporary directory, removed at the end
  std::string command_line;  // recorded in the report so anyone can regenerate it
};

// Runs every measurement, writes the report and returns the summary (what --json prints).
nlohmann::ordered_json run_visibility_bench(const VisibilityBenchParams& params);

}  // namespace cellwalk
