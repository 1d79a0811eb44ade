// `cellwalk bench visual`: the experiments of HDoV thesis §5.8 (digest §5.5) on a generated
// city, side by side in one run: Table 5.2 (storage of the three V-page schemes), Exp. 1 (node
// cache hit rate vs cache size for LRU, DoV and DoV-Time, continuous and random queries),
// Exp. 2 (search time and light-weight page I/O vs η for the schemes and the naive method),
// Exp. 3 (walkthrough frame time mean and variance vs η against REVIEW, peak memory, fidelity per
// η through the compare harness), Fig. 5.23 (search time and I/O vs world size) and a reading
// against the thesis's numbers. Writes <out>/visual.md and <out>/visual/*.csv, *.svg.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cellwalk/precompute/engine.hpp"

namespace cellwalk {

struct VisualBenchParams {
  uint64_t objects = 1500;            // buildings of the city
  int cells_per_side = 8;             // view-cell grid over the city (cells_per_side²)
  int dov_resolution = 256;           // cube-map face resolution of the DoV engine (the thesis's)
  DovCubes dov_cubes = DovCubes::kRays;  // how the DoV engine makes its cube maps
  uint32_t fanout = 8;                // M
  int queries = 400;                  // per Exp. 1 / Exp. 2 configuration
  int frames = 600;                   // Exp. 3 path ("normal" session at 10 fps: ~120 m)
  float walk_cell_size = 20.0f;       // Exp. 3: view cells along the path (the demo's 20 m)
  int fidelity_every = 20;            // Exp. 3: compare every k-th frame against ground truth
  int width = 640, height = 480;      // Exp. 3 fidelity images
  std::vector<uint64_t> scale_objects = {375, 750, 3000};  // Fig. 5.23: cities besides the default one
  int scale_cells_per_side = 3;       // Fig. 5.23: a central block of cells of the default size
  double scale_eta = 0.001;           // Fig. 5.23's η
  double render_mtri_per_s = 4.0;     // modelled rendering rate (llvmpipe, docs/renderer.md)
  std::vector<double> cache_pages = {2, 4, 8, 16, 32, 64, 128, 256};
  std::vector<double> etas = {0, 0.0005, 0.001, 0.002, 0.004, 0.008};
  std::vector<double> walk_etas = {0, 0.0003, 0.001, 0.004};
  uint64_t seed = 1;
  int threads = 0;
  std::string out_dir = "docs/results";
  std::string work_dir;               // empty = a temporary directory, removed at the end
  std::string command_line;
};

nlohmann::ordered_json run_visual_bench(const VisualBenchParams& params);

}  // namespace cellwalk
