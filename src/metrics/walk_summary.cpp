#include "cellwalk/metrics/walk_summary.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cellwalk/core/atomic_file.hpp"
#include "metrics/percentile.hpp"

namespace cellwalk {

WalkSummary summarize(const std::string& strategy, const std::vector<FrameStats>& frames) {
  WalkSummary s;
  s.strategy = strategy;
  s.frames = frames.size();
  if (frames.empty()) return s;
  std::vector<double> times;
  for (const FrameStats& f : frames) {
    times.push_back(f.frame_ms);
    s.mean_query_ms += f.query_ms;
    s.mean_io_ms += f.io_ms;
    s.mean_decode_ms += f.decode_ms;
    s.mean_render_ms += f.render_ms;
    s.total_triangles += f.triangles;
    s.total_bytes_read += f.bytes_read;
    s.cache_hits += f.cache_hits;
    s.cache_misses += f.cache_misses;
    s.stalls += f.stall ? 1 : 0;
    s.peak_resident_bytes = std::max(s.peak_resident_bytes, f.resident_bytes);
    s.peak_gpu_bytes = std::max(s.peak_gpu_bytes, f.gpu_bytes);
  }
  const double n = static_cast<double>(frames.size());
  double sum = 0;
  for (double t : times) sum += t;
  s.mean_ms = sum / n;
  double var = 0;
  for (double t : times) var += (t - s.mean_ms) * (t - s.mean_ms);
  s.stddev_ms = std::sqrt(var / n);
  s.mean_query_ms /= n;
  s.mean_io_ms /= n;
  s.mean_decode_ms /= n;
  s.mean_render_ms /= n;
  s.max_ms = *std::max_element(times.begin(), times.end());
  s.p50_ms = percentile(times, 50);
  s.p95_ms = percentile(times, 95);
  s.p99_ms = percentile(times, 99);
  return s;
}

void write_frames_csv(const std::vector<FrameStats>& frames, const std::string& file) {
  std::ostringstream out;
  out << "frame,time,frame_ms,query_ms,io_ms,decode_ms,render_ms,triangles,objects,bytes_read,"
         "cache_hits,cache_misses,resident_bytes,gpu_bytes,stall\n";
  out.setf(std::ios::fixed);
  out.precision(3);
  for (const FrameStats& f : frames)
    out << f.frame << ',' << f.time << ',' << f.frame_ms << ',' << f.query_ms << ',' << f.io_ms << ','
        << f.decode_ms << ',' << f.render_ms << ',' << f.triangles << ',' << f.objects << ','
        << f.bytes_read << ',' << f.cache_hits << ',' << f.cache_misses << ',' << f.resident_bytes
        << ',' << f.gpu_bytes << ',' << (f.stall ? 1 : 0) << '\n';
  write_file_atomically(file, out.str());
}

std::string to_json(const WalkSummary& s) {
  nlohmann::ordered_json j = {
      {"strategy", s.strategy},
      {"frames", s.frames},
      {"frame_ms", {{"mean", s.mean_ms}, {"stddev", s.stddev_ms}, {"p50", s.p50_ms},
                    {"p95", s.p95_ms}, {"p99", s.p99_ms}, {"max", s.max_ms}}},
      {"mean_split_ms", {{"query", s.mean_query_ms}, {"io", s.mean_io_ms},
                         {"decode", s.mean_decode_ms}, {"render", s.mean_render_ms}}},
      {"total_triangles", s.total_triangles},
      {"total_bytes_read", s.total_bytes_read},
      {"cache_hits", s.cache_hits},
      {"cache_misses", s.cache_misses},
      {"stalls", s.stalls},
      {"peak_resident_bytes", s.peak_resident_bytes},
      {"budget_bytes", s.budget_bytes},
      {"strategy_budget_bytes", s.strategy_budget_bytes},
      {"gpu_budget_bytes", s.gpu_budget_bytes},
      {"peak_gpu_bytes", s.peak_gpu_bytes},
      {"baseline_rss_bytes", s.baseline_rss_bytes},
      {"peak_rss_bytes", s.peak_rss_bytes},
      {"strategy_counters", nlohmann::ordered_json::object()}};
  for (const auto& [name, value] : s.strategy_counters) j["strategy_counters"][name] = value;
  return j.dump(2);
}

void write_summary_json(const WalkSummary& summary, const std::string& file) {
  write_file_atomically(file, to_json(summary) + "\n");
}

}  // namespace cellwalk
