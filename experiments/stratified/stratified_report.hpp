// `cellwalk bench stratified` (issue 17): the stratified thesis's experiments (seed 002 §6) on
// its random city, measured rather than projected:
//   table 6.1  per α: v (Eq. 2.2), b, the cells, those baked (the ones the path crosses, with a
//              margin), preprocessing time per cell (near lists and far faces) and for every
//              cell (projected from the measured rate), far-face storage (measured on the baked
//              cells, per cell and for every cell);
//   frames     brute force and `stratified` at each α walked along one path, interleaved frame
//              by frame, each with its own renderer: frame time (Figs. 6-1, 6-2; and with the
//              crossing loads taken out, Fig. 6-3's "ideal" curve), triangles, crossings, the
//              frames that loaded a cell;
//   scale      optionally, the same on a city of 10^7 triangles or more, where brute force cannot
//              keep up: stratified against brute, conv and lod in one interleaved walk;
//   fidelity   every k-th frame against ground truth: PSNR, differing pixels, missed objects,
//              pixel error, and the far field's angular error measured from the baked depth
//              against α on every frame; difference images (128 + test − truth, Figs. 6-4 to
//              6-7) of a few frames.
// Writes <out>/stratified.md and <out>/stratified/{table61,frames,summary}.csv, frame-times-seed<N>.svg
// and the images. Each path (one per seed) is walked on its own, with fresh strategies.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cellwalk/scene/generators.hpp"

namespace cellwalk {

struct StratifiedBenchParams {
  // The thesis's city: 1 km × 1 km × 67 m (§6; Appendix A's generator).
  StratifiedCityParams city{.max_height = 67.0, .blocks_x = 10, .blocks_z = 13, .seed = 3};
  std::vector<double> alphas_deg = {7.5, 1.0};  // Table 6.1's A and B
  double box = 330.0;                           // b, metres (Table 6.1)
  int resolution = 512;                         // texels per face side (§5.3)
  std::string path_kind = "fast";
  int frames = 300;                             // §6.1's path
  std::vector<uint64_t> path_seeds = {3, 6, 8};
  float along_margin = 0.0f;  // cells within this of the path are baked
  // A configuration of at most this many cells is baked whole (Table 6.1 measured for every
  // cell); a larger one only along the paths, its whole bake projected from the rate.
  uint64_t bake_all_up_to = 2000;
  int bake_threads = 2;       // bakers in the bench's process (BakePool)
  int fade_frames = 4;        // a cross-fading walker per α (stratified:fade=N); 0: none
  int width = 512, height = 512;
  double fov_deg = 90.0;
  int fidelity_every = 10;
  int images = 2;             // frames per path whose truth, test and difference images are written
  float far_level_texels = 0.5f;  // far objects baked at levels under this error (0: full detail)
  // City scale [issue 17]: > 0 also walks a city of scale_blocks × scale_blocks blocks (60: about
  // 10^7 triangles) along one path of scale_path_kind, with brute, the strategies in
  // scale_strategies and stratified at the first α, interleaved.
  int scale_blocks = 0;
  std::string scale_path_kind = "normal";
  // A normal path crosses few cells a second: a long one, with the slow strategies (a second a
  // frame at 10^7) drawn on every scale_others_every-th frame and stratified on every frame, so
  // its crossings and stalls are counted on the whole path. Compared with ground truth every
  // scale_fidelity_every-th frame (every strategy draws those).
  int scale_frames = 1800;
  int scale_others_every = 12;
  int scale_fidelity_every = 60;
  std::vector<std::string> scale_strategies = {"conv", "lod"};
  std::string out_dir = "docs/results";
  std::string work_dir;       // empty = a temporary directory, removed at the end
  std::string command_line;
};

nlohmann::ordered_json run_stratified_bench(const StratifiedBenchParams& params);

}  // namespace cellwalk
