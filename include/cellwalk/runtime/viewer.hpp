// The interactive viewer: walk or fly through a scene in a window with any strategy, see frame
// statistics on screen, toggle a bird's-eye view, and record the flown path.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cellwalk/store/world.hpp"

namespace cellwalk {

struct ViewerOptions {
  std::vector<std::string> strategies = {"brute"};  // the first is shown first; Tab cycles
  int width = 1024, height = 768;
  float fov_y_deg = 60.0f;
  std::string record_file;      // if set, records from the first frame to here (R toggles);
                                // without it R records to recorded.path
  std::string replay_file;      // if set, the camera follows this path instead of the user
  int max_frames = 0;           // quit after this many frames (0 = run until closed)
  std::string screenshot_file;  // if set, the last frame is written here as PNG
  bool birds_eye = false;       // start in the bird's-eye view
  uint64_t budget_bytes = 0;    // memory budget of the strategy and the GPU cache (0: none);
                                // split as a walk's (run_budget.hpp)
};

// What a run showed, for `view --json` (docs/json.md).
struct ViewerSummary {
  int frames = 0;
  double mean_frame_ms = 0, worst_frame_ms = 0;  // select + fetch + draw, as walk measures a frame
  double mean_objects = 0, mean_triangles = 0;   // drawn per frame
  uint64_t peak_resident_bytes = 0;              // the strategy's, at the end of a frame
  std::vector<std::string> screenshots;          // written, in order (P, then --screenshot)
  std::string recorded_file;                     // empty: nothing was recorded
  size_t recorded_frames = 0;
  bool stopped_by_signal = false;
};

// Runs until the window is closed, Escape is pressed, max_frames is reached, a replayed path
// ends or the process gets SIGINT or SIGTERM (the screenshot and the recording are still
// written). P writes screenshot-N.png in the working folder, N the first number not taken.
// Keys: W/A/S/D move, Q/E down/up (fly), mouse drag looks, Shift runs, F walk/fly,
// B bird's-eye view (what the walker is shown, seen from above, each object no finer than
// a pixel's error from up there needs when the strategy serves every level, the chosen set's
// boxes in yellow over every object's box, with the walker's frustum and, for stratified, its
// viewcell and bounding box), R starts/stops recording, P saves a screenshot, H shows the keys, Tab the next strategy,
// 1-5 switch stratified's show styles (full, near, far objects, far texture, brute), Esc quits.
// Walking keeps the eye at eye height over the floor under it (FloorProbe; steps up to half
// an eye height are climbed); the statistics wrap inside the window on a dark panel.
ViewerSummary run_viewer(const World& world, const ViewerOptions& options);

}  // namespace cellwalk
