// cellwalk bench visibility: the visibility engines of issue 4 measured side by side
// (experiments/visibility/visibility_report.hpp).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/visibility/visibility_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_visibility(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand(
      "visibility", "Visibility engines: speed, recall, tightness, storage, 4,096-cell target -> <out>/visibility.md");
  struct Args {
    VisibilityBenchParams params;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  VisibilityBenchParams& p = args->params;
  cmd->add_option("--city-objects", p.city_objects, "Objects of the ~10^6-triangle city")->capture_default_str()->check(number_in(50, 1000000));
  cmd->add_option("--plant-units", p.plant_units, "Units per side of the ~10^6-triangle plant")->capture_default_str()->check(number_in(1, 64));
  cmd->add_flag("--large", p.large, "Also the ~10^7-triangle city and plant (long)");
  cmd->add_option("--large-city-objects", p.large_city_objects, "Objects of the --large city")->capture_default_str()->check(number_in(50, 1e7));
  cmd->add_option("--large-plant-units", p.large_plant_units, "Units per side of the --large plant")->capture_default_str()->check(number_in(1, 1000));
  cmd->add_option("--cell-size", p.cell_size, "View cell side at eye height (m)")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--check", p.checked_cells, "Cells checked against ground truth per world")->capture_default_str()->check(number_in(1, 10000));
  cmd->add_option("--dov-cells", p.dov_cells, "Of those, cells checked with the dov engine")->capture_default_str()->check(number_in(0, 10000));
  cmd->add_option("--truth-points", p.truth_points, "Ground truth: random points per cell besides the corners")->capture_default_str();
  cmd->add_option("--truth-resolution", p.truth_resolution, "Ground truth: cube-map face resolution")->capture_default_str()->check(number_in(16, 4096));
  cmd->add_option("--refine-levels", p.refine_levels, "Conservative refinement levels compared")->capture_default_str()->check(number_in(0, 8));
  cmd->add_option("--block", p.storage_side, "Side (in cells) of the block computed for storage and the target")->capture_default_str()->check(number_in(1, 64));
  cmd->add_option("--threads", p.threads, "Threads of the block run (the target says 2 cores)")->capture_default_str()->check(number_in(1, 256));
  cmd->add_option("--out", p.out_dir, "Directory of the report (visibility.md and visibility/)")->capture_default_str();
  cmd->add_option("--work-dir", p.work_dir, "Where the worlds go (default: a temporary directory)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    const nlohmann::ordered_json summary = run_visibility_bench(args->params);
    if (args->json) {
      print_json("bench visibility", summary);
      return;
    }
    for (const auto& sentence : summary["reading"]) std::printf("%s\n", sentence.get<std::string>().c_str());
    std::printf("wrote %s/visibility.md in %.0f s\n", args->params.out_dir.c_str(), summary["seconds"].get<double>());
  });
}

}  // namespace cellwalk::app
