// Exp. 3 of `cellwalk bench visual` (HDoV thesis §5.8.5, Table 5.3, Figs. 5.24–5.27): VISUAL at
// several η and REVIEW replay one path; frame time, peak memory, and the fidelity of each against
// the full-detail world through the compare harness (src/metrics/fidelity.cpp, `cellwalk compare`).
#pragma once

#include <string>
#include <vector>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/metrics/fidelity.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "experiments/visual/visual_world.hpp"

namespace cellwalk::visual_bench {

struct WalkRun {
  std::string label;
  double eta = -1;                // VISUAL's η; -1 for REVIEW
  bool full = false;              // VISUAL-full: visible objects at level 0 (MAXDOV → 0), η alone
  std::vector<double> frame_ms;   // per frame: measured select + fetches + modelled render
  uint64_t peak = 0, triangles = 0, queries = 0, ios = 0;
  double query_ms = 0;            // Σ over queries (VISUAL: flip + search; REVIEW: its queries)
  FidelitySummary fidelity;
};

// Replays `path` headless with VISUAL (indexed-vertical, DoV-Time node cache) at each of
// p.walk_etas, with VISUAL-full (the same, visible objects at level 0 instead of eq. 5.6's
// level) at each of them, and with REVIEW (400 m query boxes), then compares every p.fidelity_every-th frame
// of each against ground truth at p.width × p.height. REVIEW comes last.
std::vector<WalkRun> run_walks(const VisualBenchParams& p, const TreeWorld& w, const CameraPath& path);

}  // namespace cellwalk::visual_bench
