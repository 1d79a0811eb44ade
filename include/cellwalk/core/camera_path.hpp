// Camera paths: the recorded or generated sequence of viewpoints every comparison replays.
//
// Text format (docs/paths.md): a first line "# cellwalk path 1", further lines starting
// with '#' are comments (one, "# world <name> <identity>", names the world the path was made
// for), then one line per frame:
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

// The world a path was made for: a name for people and an identity to compare; both empty
// when the file does not say (paths written before the line existed, recorded paths).
struct PathWorld {
  std::string name;
  std::string identity;
  bool known() const { return !identity.empty(); }
};

struct CameraPath {
  std::vector<PathFrame> frames;
  PathWorld world;
};

CameraPath read_path(const std::string& file);
// Writes to a temporary name and renames: an existing path file survives a failure.
void write_path(const CameraPath& path, const std::string& file);

// Places `camera` at a frame (keeps its lens).
void apply(const PathFrame& frame, Camera& camera);

}  // namespace cellwalk
