// `cellwalk bench vlod` (issue 14): vLOD (seed 001, Chhugani et al. 2003) reproduced and set
// beside the other strategies in one run, on generated worlds built for the purpose:
//   walks     per world (city, plant) and path kind (normal, fast): brute, conv, review and
//             vlod at each pixel bound (and vlod without frustum culling), rendered with the
//             real renderer under one hard budget (a share of the world file, at least a
//             floor): frame time, triangles drawn (Fig. 11: against frustum culling alone,
//             which is brute), triangles per pixel, stalls, peak resident bytes; then every
//             k-th frame of each against ground truth (missed objects, pixel error, differing
//             pixels), all against one truth rendering per frame;
//   storage   the Δs of every world (the scale table's cities too) in each codec against
//             bitmasks and 32-bit id lists, their
//             decode time, R(M) in the world's order and the Hamming-TSP order (§3), Δs
//             against the world file;
//   coherence frames that change cell, |Δ| / |vLOD| at each change (Fig. 10), section bytes
//             read and geometry bytes read per change;
//   scale     the normal path on cities of growing size: vlod's frame time against the
//             smallest city's (the seed's claim: independent of model size) and brute's;
//   tightness vLOD's sets against 125-point sampling (8 corners, 6 face centres, the centre
//             and 110 random points) on a few cells (seed: 2–10×);
//   precompute seconds per cell.
// Writes <out>/vlod.md and <out>/vlod/{walks,storage,coherence,scale,tightness}.csv, triangles.svg,
// once the walked worlds are measured and again at the end. A run the budget cannot hold is a
// row saying why, in every table.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cellwalk {

struct VlodBenchParams {
  uint64_t city_objects = 560;  // ~10^6 triangles (1,790 per object on average)
  int plant_units = 4;          // 4 × 4 units at detail 2: ~0.96 M triangles
  double plant_detail = 2.0;
  // The scale table's cities, by object count: ~10^6 and ~10^7 triangles (56,000 for ~10^8).
  std::vector<uint64_t> scale_objects = {560, 5600};
  std::vector<std::string> path_kinds = {"normal", "fast"};
  int frames = 150;
  float cell_size = 20.0f;     // grid cells at eye height, metres
  float along_margin = 20.0f;  // cells within this of a path are computed (pvs --along)
  // The rule's bounds, pixels; the first is the seed's (< 1 px) and the one the scale and
  // storage tables use.
  std::vector<double> pixel_errors = {1.0, 0.25};
  int width = 640, height = 480;
  double budget_fraction = 0.02;  // the run's budget: this share of the world file ...
  double min_budget_mib = 64;     // ... but at least this many MiB (small worlds)
  int fidelity_every = 10;
  int tightness_cells = 6;
  uint64_t seed = 1;
  int threads = 0;  // precompute threads (0 = all cores)
  std::string out_dir = "docs/results";
  std::string work_dir;      // empty = a temporary directory, removed at the end
  std::string command_line;  // recorded in the report so anyone can regenerate it
};

// Runs every measurement, writes the report and returns the summary (what --json prints).
nlohmann::ordered_json run_vlod_bench(const VlodBenchParams& params);

}  // namespace cellwalk
