// The interactive viewer: walk or fly through a scene in a window with any strategy, see frame
// statistics on screen, toggle a bird's-eye view, and record the flown path.
#pragma once

#include <string>

#include "cellwalk/store/world.hpp"

namespace cellwalk {

struct ViewerOptions {
  std::string strategy = "brute";
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

// Runs until the window is closed, Escape is pressed, max_frames is reached, a replayed path
// ends or the process gets SIGINT or SIGTERM (the screenshot and the recording are still
// written). P writes screenshot-N.png in the working folder, N the first number not taken.
// Keys: W/A/S/D move, Q/E down/up (fly), mouse drag looks, Shift runs, F walk/fly,
// B bird's-eye view (what the walker is shown, seen from above, with its frustum and, for
// stratified, its viewcell and bounding box), R starts/stops recording, P saves a screenshot,
// 1-5 switch stratified's show styles (full, near, far objects, far texture, brute), Esc quits.
void run_viewer(const World& world, const ViewerOptions& options);

}  // namespace cellwalk
