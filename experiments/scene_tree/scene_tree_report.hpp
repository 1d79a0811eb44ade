// `cellwalk bench scene-tree`: HDoV thesis ch. 6's experiments (§6.3, Table 6.1, Figs. 6.4–6.7;
// digest 000 §5.6) on a generated city, side by side in one run: CONV (hierarchical frustum
// culling), VSC at several η and PB at several polygon budgets replay the same path; frame time,
// triangles and nodes visited per frame, and fidelity against the full-detail ground truth
// (differing pixels, objects missed, PSNR) for every setting, so speed against quality is a
// curve. Writes <out>/scene-tree.md and <out>/scene-tree/{frames,summary,fidelity}.csv, summary.json
// and the SVG figures.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cellwalk {

struct SceneTreeBenchParams {
  uint64_t objects = 1200;  // of the generated city (1 % bunnies, as `generate city`)
  uint64_t seed = 1;
  int frames = 360;         // of the walk ("normal" session)
  double fps = 10.0;        // path sampling: 360 frames at 10 fps, ~70 m at walking speed
  float cell_size = 20.0f;  // view cells: a grid over the path's surroundings only
  int dov_resolution = 64;  // cube-map face pixels per side (the thesis: 256; see the report)
  std::vector<double> etas = {0.0, 0.0001, 0.001, 0.01};
  std::vector<uint64_t> budgets = {20000, 40000, 60000, 80000};
  int rounds = 2;           // timed replays per setting, interleaved; the fastest is reported
  int fidelity_every = 8;   // compare every k-th frame against ground truth
  int width = 640, height = 480;
  int threads = 0;          // world build and DoV precomputation (0 = all cores)
  std::string out_dir = "docs/results";
  std::string work_dir;     // scene, world and tree files; empty = a temporary directory
  std::string command_line; // recorded in the report
};

// Runs everything, writes the report files and returns the summary (what --json prints).
// Long steps draw progress lines on stderr. Throws Error when a step fails, naming it.
nlohmann::ordered_json run_scene_tree_bench(const SceneTreeBenchParams& params);

}  // namespace cellwalk
