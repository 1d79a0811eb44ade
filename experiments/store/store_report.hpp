// `cellwalk bench store`: measures the world store against the references it should be judged
// by, side by side in one run (DESIGN.md "Measuring": timings are ratios, absolute times vary):
//   build        build_world vs meshopt_simplify once to 1/2 and build_lod_chain alone, on the
//                same objects; peak RSS of the build in a child process (its own VmHWM).
//   I/O          random 4 KiB and sequential reads through PageFile (cache bypassed) and
//                WorldFile::read (checksums verified) vs a raw O_DIRECT pread loop, interleaved.
//   decode       decode_mesh on the world's encoded levels vs memcpy of the decoded bytes.
//   cache        hit ratio of LRU, DPLRU (HDoV thesis §4.2.4), DoV and DoV-Time (thesis §5.7)
//                and the Li–Chiang hybrid relevance cache on one recorded frustum-culling trace,
//                at budgets from 2 % to 100 % of the trace's working set.
// Writes <out>/store.md and <out>/store/{build,io,decode,cache}.csv, summary.json,
// hit_ratio.svg.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cellwalk {

struct StoreBenchParams {
  uint64_t objects = 1000;  // objects of the generated city measured
  // Also generate and build a ~10^8-triangle city (large_objects objects), peak RSS and time.
  bool large = false;
  uint64_t large_objects = 60000;  // docs/generators.md: 106 M triangles at 1 % landmarks
  // Build threads. 1 by default so build and the single-threaded references share a core.
  int threads = 1;
  int path_frames = 1800;        // frames of the walk whose requests make the cache trace (60 s)
  int io_rounds = 5;             // interleaved rounds of each I/O and decode measurement
  uint64_t random_reads = 2000;  // 4 KiB reads per method and round
  // Bytes per sequential pass; the geometry section is read round and round until this many,
  // so a small world still gives a pass long enough to time.
  uint64_t sequential_bytes = 64ull << 20;
  std::vector<double> budget_fractions = {0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0};
  std::string out_dir = "docs/results";
  // Scene and world files; empty = a fresh directory under the system's temporary directory,
  // removed at the end.
  std::string work_dir;
  std::string command_line;  // recorded in the report so anyone can regenerate it
};

// Runs every measurement, writes the report files and returns the summary (what --json prints).
// Long steps draw progress lines on stderr. Throws Error when a step fails (e.g. the child
// build), naming the step.
nlohmann::ordered_json run_store_bench(const StoreBenchParams& params);

}  // namespace cellwalk
