// `cellwalk bench import` (issue 16, item 1): importing a model larger than memory. Height-field
// PLY files of growing size are imported by the cellwalk binary in a child process, read whole
// and streamed within each --memory; the kernel's peak resident memory of each child (wait4),
// its resident memory at start (from its --json), wall time, patches. Writes <out>/import.md
// and <out>/import/runs.csv.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cellwalk {

struct ImportBenchParams {
  std::vector<uint32_t> sides = {1000, 3000};  // vertices a side: 2 (side - 1)² triangles
  bool large = false;                          // also a side of 9,000: 162 M triangles, a 3.1 GB file
  std::vector<double> memory_mib = {32, 256};
  std::string work_dir;  // default: a temporary directory
  std::string out_dir = "docs/results";
  std::string command_line;
};

nlohmann::ordered_json run_import_bench(const ImportBenchParams& params);

}  // namespace cellwalk
