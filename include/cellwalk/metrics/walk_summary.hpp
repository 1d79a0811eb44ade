// A walk's frames summarised the same way for every strategy, and written as CSV and JSON
// (src/metrics/walk_summary.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
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
  uint64_t budget_bytes = 0;         // the process budget the walk ran under (0: none)
  uint64_t strategy_budget_bytes = 0;  // its parts (cellwalk/runtime/run_budget.hpp)
  uint64_t gpu_budget_bytes = 0;
  uint64_t peak_gpu_bytes = 0;
  // The process: its fixed baseline (code, GL driver, framebuffers, measured before the world
  // opens) and its peak resident bytes during this run, measured by the kernel (VmHWM). With a
  // budget, peak_rss_bytes <= budget_bytes + baseline_rss_bytes is what the budget promises.
  uint64_t baseline_rss_bytes = 0;
  uint64_t peak_rss_bytes = 0;
  std::vector<std::pair<std::string, double>> strategy_counters;  // Strategy::walk_counters()
};

WalkSummary summarize(const std::string& strategy, const std::vector<FrameStats>& frames);

// CSV with a header row, one row per frame; JSON for the summary. Both written to a temporary
// name and renamed.
void write_frames_csv(const std::vector<FrameStats>& frames, const std::string& file);
void write_summary_json(const WalkSummary& summary, const std::string& file);
std::string to_json(const WalkSummary& summary);

}  // namespace cellwalk
