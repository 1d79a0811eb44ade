// `cellwalk bench pvs-stream` (issue 20): Zheng's §7.5 simulation (seed 004; digest §5, "PVS
// simulation") from our code: the synthetic 900-building city with 20 m view cells and its PVS
// table (5 % visible, 60 % adjacent overlap, both measured), the two 3,000-step routes, SNP and
// PBNP over the same 9-entry cache with delta transmission, and Table 7.2 (transactions, cache
// swaps, objects per transaction, first prefetch) beside the thesis's; PBNP's region band (which
// the thesis does not give) swept; the objects sent at each step plotted (Figures 7.7, 7.8).
// Then the client over real sockets (pvs_stream_sockets.hpp). Writes <out>/pvs-stream.md and
// <out>/pvs-stream/{seeds.csv,band.csv,sockets.csv,route*.svg}.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cellwalk/systems/pvs_stream/pvs_simulation.hpp"
#include "experiments/pvs_stream/pvs_stream_sockets.hpp"

namespace cellwalk {

struct PvsStreamBenchParams {
  pvs_stream::SyntheticCityParams city;
  pvs_stream::RouteParams route;
  double band = 0.25;                              // PBNP's region band, a fraction of a cell
  std::vector<double> bands = {0.1, 0.2, 0.25, 0.33, 0.45};  // swept for PBNP
  std::vector<uint64_t> seeds = {1, 2, 3};         // route seeds (route 1 varies, route 2 does not)
  bool sockets = true;  // also the walks over sockets (pvs_stream_sockets.hpp)
  PvsSocketBenchParams net;
  std::string out_dir = "docs/results";
  std::string command_line;
};

nlohmann::ordered_json run_pvs_stream_bench(const PvsStreamBenchParams& params);

}  // namespace cellwalk
