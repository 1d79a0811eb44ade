// `cellwalk bench review`: the experiments of HDoV thesis §4.4 (digest §5.4) on a generated
// city, side by side in one run: Table 4.1 (disk I/Os per query, BOX vs Optimal), Fig. 4.17
// (k sweep), Fig. 4.18 (DPLRU vs LRU over index-cache sizes), Figs. 4.19–4.21 (frame time mean,
// variance and series vs cell size for Optimal/NC/NP/BOX), Table 4.2 (ViewCulling), Fig. 4.22
// (search time vs world size), and the fidelity of REVIEW's spatial queries against ground truth.
// Frames are replayed headless: frame time = the strategy's measured CPU work (search, decode,
// culling) + a render time modelled from the triangles drawn + the disk time of its demand
// queries modelled at a 2002 disk's cost; a prefetch's disk time overlaps the frames after it
// (the thesis's prefetch thread) and only what is left when its cell is needed is charged.
// Writes <out>/review.md and <out>/review/*.csv, *.svg, summary.json.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cellwalk {

struct ReviewBenchParams {
  uint64_t objects = 24000;          // the main city; the world-size sweep adds 1/4 and 1/2 of it
  double session_km = 6.0;           // each session's length: ~60 BOX queries at SF 2
  double path_fps = 10.0;            // frames per second of path time
  // Session speeds, m/s, in the order fast, slow, turning, backward, normal: a fly-through, so
  // that k·v at k = 0.8 is a sizeable share of the disk cell's margin (docs/review.md).
  std::vector<double> speeds = {120, 15, 40, 40, 50};
  double disk_seek_ms = 8.0;         // modelled 2002 disk: per random access (node page, object)
  double disk_page_ms = 0.2;         // and per 4 KiB page transferred (~20 MB/s)
  double depth = 200.0;              // frustum depth, metres (the thesis: 1 km; see docs/review.md)
  double scale_factor = 2.0;         // SF of the runs that do not sweep it
  uint32_t fanout = 32;              // R-tree M
  double buffer_mib = 20.0;          // the thesis's 20 MB cap, as the object buffer
  double cache_mib = 1.0;            // the thesis's default index cache
  double render_mtri_per_s = 4.0;    // llvmpipe's measured rate (docs/renderer.md)
  std::vector<double> ks = {0, 0.4, 0.8, 1.2, 1.6, 2.4};
  std::vector<double> cache_kib = {16, 32, 64, 128, 256, 1024};
  std::vector<double> cell_sizes = {1.0, 1.2, 1.5, 2.1, 2.5, 3.1};
  int fidelity_every = 60;           // compare every n-th frame of one session (0 = skip)
  uint64_t seed = 1;
  std::string out_dir = "docs/results";
  std::string work_dir;              // empty = a temporary directory, removed at the end
  std::string command_line;
};

// Runs everything, writes the report, returns the summary. Progress on stderr.
nlohmann::ordered_json run_review_bench(const ReviewBenchParams& params);

}  // namespace cellwalk
