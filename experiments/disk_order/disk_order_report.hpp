// `cellwalk bench disk-order` (issue 14): vLOD §3's Table 1 (seed 001, digest §3.5) reproduced on
// planted consecutive-ones matrices (planted_matrix.hpp) at the seed's sizes: time of the k-NN
// lists, of the greedy seed tour, of the first improvement and of each later one, and the
// improvement in runs R(M) after the first iteration and after many, for short rows (each up to
// 60 columns, 4 rows a column) and long ones (up to 1,000 columns, a row per 2 columns), with the
// exact lists and the sampled ones, beside the seed's figures. Writes <out>/disk-order.md and
// <out>/disk-order/table1.csv.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cellwalk {

struct DiskOrderBenchParams {
  std::vector<uint32_t> sizes = {500, 1000, 3000, 9000, 27000};  // columns (the seed's sizes)
  uint32_t max_iterations = 100000;
  double max_seconds = 10;  // per run, on the iterations after the first
  uint64_t seed = 1;
  std::string out_dir = "docs/results";
  std::string command_line;
};

nlohmann::ordered_json run_disk_order_bench(const DiskOrderBenchParams& params);

}  // namespace cellwalk
