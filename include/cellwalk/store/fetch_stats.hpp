// What fetching geometry from the store costs, counted by the store where it happens and added
// into a frame's statistics (cellwalk/strategy/frame_stats.hpp).
#pragma once

#include <cstdint>

namespace cellwalk {

struct FetchStats {
  double io_ms = 0.0;      // reading from the store / file
  double decode_ms = 0.0;  // turning bytes into meshes
  uint64_t bytes_read = 0;
  uint64_t cache_hits = 0;
  uint64_t cache_misses = 0;
};

}  // namespace cellwalk
