// Camera paths: the recorded or generated sequence of viewpoints every comparison replays.
//
// Text format (docs/path-format.md): a first line "# cellwalk path 1", further lines starting
// with '#' are comments, then one line per frame:
//   <time s> <x> <y> <z> <yaw deg> <pitch deg>
// Times are non-decreasing. Positions are metres in world space.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cellwalk/core/camera.hpp"

namespace cellwalk {

struct PathFrame {
  double time = 0.0;
  Vec3 position{0.0f};
  float yaw_deg = 0.0f;
  float pitch_deg = 0.0f;
};

struct CameraPath {
  std::vector<PathFrame> frames;
};

CameraPath read_path(const std::string& file);
// Writes to a temporary name and renames: an existing path file survives a failure.
void write_path(const CameraPath& path, const std::string& file);

// Places `camera` at a frame (keeps its lens).
void apply(const PathFrame& frame, Camera& camera);

}  // namespace cellwalk
