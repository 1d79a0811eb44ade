// A walk's frames summarised the same way for every strategy, and written as CSV and JSON
// (src/metrics/walk_summary.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cellwalk/strategy/frame_stats.hpp"

namespace cellwalk {

struct WalkSummary {
  std::string strategy;
  size_t frames = 0;
  double mean_ms = 0, stddev_ms = 0, p50_ms = 0, p95_ms = 0, p99_ms = 0, max_ms = 0;
  double mean_query_ms = 0, mean_io_ms = 0, mean_decode_ms = 0, mean_render_ms = 0;
  uint64_t total_triangles = 0, total_bytes_read = 0, cache_hits = 0, cache_misses = 0;
  uint64_t stalls = 0;
  uint64_t peak_resident_bytes = 0;  // the strategy's exact peak (set by the caller), or the
                                     // largest per-frame value
  uint64_t budget_bytes = 0;         // the memory budget the walk ran under (0: none)
  uint64_t peak_gpu_bytes = 0;
};

WalkSummary summarize(const std::string& strategy, const std::vector<FrameStats>& frames);

// CSV with a header row, one row per frame; JSON for the summary. Both written to a temporary
// name and renamed.
void write_frames_csv(const std::vector<FrameStats>& frames, const std::string& file);
void write_summary_json(const WalkSummary& summary, const std::string& file);
std::string to_json(const WalkSummary& summary);

}  // namespace cellwalk
