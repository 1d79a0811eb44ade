// `cellwalk bench pvs-stream`, its second part (issue 20): the PVS streaming client
// (pvs-stream strategy) over real loopback sockets to a PVS server on a generated city with
// conservative visible sets over a grid, each link (one-way delay × rate, both directions) and
// prefetcher (SNP, PBNP, speed-aware) walking the same paths at the paths' own speed: stall
// frames, frames drawn late, visible objects missed (the cell's stored set, frustum-culled, less
// what was drawn), bytes per cell crossing, start-up time, transactions and rows replaced. Then
// many clients on one server: bytes served per second, request latency (p50, p99), the
// sessions' memory on the server. The same walks served by nginx (HTTP range requests) beside.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cellwalk {

struct PvsSocketBenchParams {
  uint64_t objects = 300;     // the city's buildings
  uint64_t city_seed = 1;
  double cell = 10.0;         // m, the view cells' side
  int frames = 600;           // frames of each path (30 per second of path time)
  uint64_t path_seed = 1;
  std::vector<std::string> kinds = {"normal", "fast"};
  std::vector<double> latencies = {1, 80, 350};  // ms, one way, each direction
  std::vector<double> bandwidths = {10, 100};    // Mbit/s, each direction
  std::vector<std::string> prefetchers = {"snp", "pbnp", "speed"};
  // The same walks with no PVS server: the world file behind Debian's nginx, read by range
  // requests (each delayed by the link's round trip, its bytes at its rate); none: not run.
  std::vector<std::string> nginx_prefetchers = {"pbnp"};
  // Many clients on one server: each walks the first path kind from its own starting frame.
  int clients = 64;
  double clients_latency_ms = 80, clients_bandwidth_mbit = 100;  // the server's link to each client
  std::string work_dir;  // "": a temporary one
};

struct PvsSocketBenchResult {
  std::string markdown;  // the report's section
  nlohmann::ordered_json json;     // one object per walk
  nlohmann::ordered_json clients;  // the many clients (null when not run)
  bool ordering_holds = false;  // PBNP replaced fewer rows than SNP on every path and link
  bool target_met = false;      // 80 ms / 100 Mbit/s, normal path: 0 missed, stalls < 1 %
};

// REQUIRES: out_dir exists; writes out_dir/pvs-stream/sockets.csv.
PvsSocketBenchResult run_pvs_socket_bench(const PvsSocketBenchParams& params, const std::string& out_dir);

}  // namespace cellwalk
