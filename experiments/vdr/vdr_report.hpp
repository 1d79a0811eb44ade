// `cellwalk bench vdr` (issue 19): Zheng's chapters 3–6 (seed 004; digest §5) from our code, on
// the CGAL models and a generated large mesh: Tables 3.2–3.3 (the three DAG builders), 4.1–4.3
// and Fig. 4.12 (the three traversals, client memory, fronts, accuracy against priority), 5.1
// (sequential against one-frame parallel on a LAN), 6.1 and Fig. 6.8 (RTT 80–350 ms, span and
// prediction: frame time, accuracy, unmodified frames), the thesis's client beside ours (turn
// prediction, a server-held budget); then many clients on one server. Writes <out>/vdr.md and
// <out>/vdr/{*.csv,*.svg}.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cellwalk {

struct VdrBenchParams {
  // Model files; a bare name is looked up in data/cgal/meshes.
  std::vector<std::string> models = {"bunny00.off", "armadillo.off", "ChineseDragon-10kv.off"};
  uint64_t large_triangles = 1000000;  // a generated bumpy sphere of about this many; 0: none
  uint32_t base_triangles = 1000;
  uint32_t budget = 60000, n = 500;    // B and N, the thesis's
  float tau = 0.001f, alpha = 0.6f;
  std::string units = "length";        // thesis (raw QE) or length
  std::vector<double> rtts = {80, 170, 260, 350};  // ms, split evenly between the directions
  std::vector<uint32_t> spans = {1, 3, 6, 9, 12};  // Fig. 6.8's, at the second RTT
  double lan_rtt = 1.0;
  double frame_ms = 30.0;              // frames last at least this (the thesis ran at about 30 fps)
  bool render = true;                  // draw each frame (llvmpipe); false: T_r = 0
  int width = 640, height = 480;
  int clients = 64;
  double clients_rtt = 80.0;
  int alone = 8;                       // of the clients, walked again alone for comparison
  std::string out_dir = "docs/results";
  std::string command_line;
};

nlohmann::ordered_json run_vdr_bench(const VdrBenchParams& params);

}  // namespace cellwalk
