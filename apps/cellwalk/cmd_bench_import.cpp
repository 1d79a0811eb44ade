// cellwalk bench import: importing a model larger than memory (experiments/import/import_report.hpp).
#include <cstdio>
#include <memory>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/import/import_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_import(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand("import", "Import: streamed within a memory bound against read whole -> <out>/import.md");
  struct Args {
    ImportBenchParams params;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  ImportBenchParams& p = args->params;
  cmd->add_option("--sides", p.sides, "Vertices a side of the height fields imported (2 (side - 1)² triangles each)")
      ->capture_default_str()->check(integer_in(2, 40000));
  cmd->add_flag("--large", p.large, "Also a side of 9,000: 162 M triangles, a 3.1 GB file over the 2 GiB read whole (long; ~25 GB of disk)");
  cmd->add_option("--memory", p.memory_mib, "--memory of the streamed imports, MiB")->capture_default_str()->check(number_in(32, 1 << 20));
  cmd->add_option("--work-dir", p.work_dir, "Where the models, scenes and scratch files go (default: a temporary directory)");
  cmd->add_option("--out", p.out_dir, "Directory of the report (import.md and import/)")->capture_default_str();
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    const nlohmann::ordered_json summary = run_import_bench(args->params);
    if (args->json) {
      print_json("bench import", summary);
      return;
    }
    for (const auto& r : summary["runs"]) {
      if (r.contains("refused")) continue;
      std::printf("%6u %-9s memory %6.0f MiB: %7.1f s, peak %7.1f MiB (%.1f at start)\n", r["side"].get<uint32_t>(),
                  r["mode"].get<std::string>().c_str(), r["memory_mib"].get<double>(), r["seconds"].get<double>(),
                  r["peak_rss_bytes"].get<double>() / 1048576.0, r["baseline_rss_bytes"].get<double>() / 1048576.0);
    }
    std::printf("wrote %s/import.md in %.0f s\n", args->params.out_dir.c_str(), summary["seconds"].get<double>());
  });
}

}  // namespace cellwalk::app
