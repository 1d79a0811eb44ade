// The thesis's two camera paths around one model (seed 004, §4.6; digest §5 "Camera paths"),
// placed by the model's bounding sphere (centre c, radius R), eye on the +z side, y up:
//   path 1, 180 frames at uniform speed: approach from 6R to 1.2R (frames 0–109), scan bottom to
//           top (110–154), scan right to left (155–179), looking at the model all the time;
//   path 2, 194 frames: approach from 6R to 1.8R (0–59), orbit accelerating from rest
//           (60–109), orbit at 6° a frame (110–193).
#pragma once

#include <cstdint>
#include <vector>

#include "cellwalk/core/geometry.hpp"

namespace cellwalk::vdr {

struct VdrFrame {
  Vec3 eye{0.0f}, aim{0.0f};
};

// which: 1 or 2 (else Error). REQUIRES: a non-empty bounds.
std::vector<VdrFrame> thesis_path(int which, const Aabb& bounds);

}  // namespace cellwalk::vdr
