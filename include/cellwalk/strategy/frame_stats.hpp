// What every strategy reports per frame, the same way, so strategies can be compared.
#pragma once

#include <cstdint>

#include "cellwalk/store/fetch_stats.hpp"

namespace cellwalk {

// The store's part (io, decode, bytes, hits) is its FetchStats; the rest is the strategy's and
// the frame loop's.
struct FrameStats : FetchStats {
  int frame = 0;
  double time = 0.0;  // path time, seconds
  double query_ms = 0.0;   // choosing what to draw (culling, index search, visibility)
  double render_ms = 0.0;  // drawing, including upload and glFinish
  double frame_ms = 0.0;   // wall time of the whole frame
  uint64_t triangles = 0;
  uint64_t objects = 0;
  uint64_t resident_bytes = 0;  // the strategy's memory (under its budget) at the end of the frame
  uint64_t gpu_bytes = 0;       // the renderer's buffer cache (under its own budget)
  bool stall = false;           // the frame waited for data it needed
};

}  // namespace cellwalk
