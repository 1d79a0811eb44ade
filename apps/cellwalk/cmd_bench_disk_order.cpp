// cellwalk bench disk-order: vLOD §3's Table 1 (experiments/disk_order/disk_order_report.hpp).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/disk_order/disk_order_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_disk_order(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand("disk-order", "vLOD §3: the Hamming-TSP disk order, Table 1 -> <out>/disk-order.md");
  struct Args {
    DiskOrderBenchParams params;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  DiskOrderBenchParams& p = args->params;
  cmd->add_option("--sizes", p.sizes, "Columns of the matrices (the seed's: 500 1000 3000 9000 27000)")->capture_default_str()->check(integer_in(2, 10000000));
  cmd->add_option("--iterations", p.max_iterations, "Improvement iterations at most")->capture_default_str()->check(integer_in(0, 100000000));
  cmd->add_option("--seconds", p.max_seconds, "Seconds at most for the iterations after the first, per run")->capture_default_str()->check(number_in(0, 1e6));
  cmd->add_option("--seed", p.seed, "Matrix and kick seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--out", p.out_dir, "Directory of the report (disk-order.md and disk-order/)")->capture_default_str();
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    const nlohmann::ordered_json summary = run_disk_order_bench(args->params);
    if (args->json) {
      print_json("bench disk-order", summary);
      return;
    }
    for (const auto& r : summary["runs"])
      std::printf("%6u %-5s %-7s kNN %7.3f s  Imp1 %7.2f  final R %llu (planted %llu)\n", r["columns"].get<uint32_t>(),
                  r["long_rows"].get<bool>() ? "long" : "short", r["sampled"].get<bool>() ? "sampled" : "exact",
                  r["knn_seconds"].get<double>(), r["imp1"].get<double>(),
                  (unsigned long long)r["runs_final"].get<uint64_t>(), (unsigned long long)r["runs_planted"].get<uint64_t>());
    std::printf("wrote %s/disk-order.md in %.0f s\n", args->params.out_dir.c_str(), summary["seconds"].get<double>());
  });
}

}  // namespace cellwalk::app
