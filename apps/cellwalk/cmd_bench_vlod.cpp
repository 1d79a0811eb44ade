// cellwalk bench vlod: vLOD (seed 001) reproduced and set beside the other strategies
// (experiments/vlod/vlod_report.hpp).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/vlod/vlod_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_vlod(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand(
      "vlod", "vLOD (seed 001): walkthroughs side by side, Δ storage, coherence, scale, tightness -> <out>/vlod.md");
  struct Args {
    VlodBenchParams params;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  VlodBenchParams& p = args->params;
  cmd->add_option("--city-objects", p.city_objects, "Objects of the walked city (560: ~10^6 triangles)")->capture_default_str()->check(number_in(50, 1000000));
  cmd->add_option("--plant-units", p.plant_units, "Units per side of the walked plant (4: ~10^6 triangles)")->capture_default_str()->check(number_in(1, 64));
  cmd->add_option("--plant-detail", p.plant_detail, "Tessellation of the plant")->capture_default_str()->check(number_in(0.25, 16));
  cmd->add_option("--scale-objects", p.scale_objects, "Objects of the scale table's cities (5600: ~10^7 triangles, 56000: ~10^8)")->capture_default_str()->check(number_in(50, 1e7));
  cmd->add_option("--paths", p.path_kinds, "Path kinds walked (normal, fast, slow, turning, ...)")->capture_default_str()->check(session_kind_check());
  cmd->add_option("--frames", p.frames, "Frames per path")->capture_default_str()->check(integer_in(2, 100000));
  cmd->add_option("--cell-size", p.cell_size, "View cell side at eye height (m)")->capture_default_str()->check(number_in(1, 10000));
  cmd->add_option("--along-margin", p.along_margin, "Cells within this of a path are computed (m)")->capture_default_str()->check(number_in(0, 10000));
  cmd->add_option("--pixel-error", p.pixel_errors, "The vLOD rule's bounds walked, pixels; the first is the seed's and serves the scale table")->capture_default_str()->check(number_in(0.01, 100));
  cmd->add_option("--width", p.width, "Image width")->capture_default_str()->check(integer_in(16, 4096));
  cmd->add_option("--height", p.height, "Image height")->capture_default_str()->check(integer_in(16, 4096));
  cmd->add_option("--budget-fraction", p.budget_fraction, "Each run's memory budget as a share of the world file")->capture_default_str()->check(number_in(0.001, 10));
  cmd->add_option("--min-budget", p.min_budget_mib, "... but at least this many MiB")->capture_default_str()->check(number_in(1, 1 << 20));
  cmd->add_option("--fidelity-every", p.fidelity_every, "Compare every k-th frame with ground truth")->capture_default_str()->check(integer_in(1, 100000));
  cmd->add_option("--tightness-cells", p.tightness_cells, "Cells whose vLOD is set against 125-point sampling")->capture_default_str()->check(integer_in(0, 100000));
  cmd->add_option("--seed", p.seed, "World and path seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--threads", p.threads, "Precompute threads (0 = all cores)")->capture_default_str()->check(thread_count());
  cmd->add_option("--out", p.out_dir, "Directory of the report (vlod.md and vlod/)")->capture_default_str();
  cmd->add_option("--work-dir", p.work_dir, "Where the worlds go (default: a temporary directory)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    const nlohmann::ordered_json summary = run_vlod_bench(args->params);
    if (args->json) {
      print_json("bench vlod", summary);
      return;
    }
    for (const auto& s : summary["scale"])
      std::printf("%-10s brute %8.1f ms  vlod %7.1f ms  (%.2f x the smallest city's)\n", s["world"].get<std::string>().c_str(),
                  s["brute_ms"].get<double>(), s["vlod_ms"].get<double>(), s["vlod_over_smallest"].get<double>());
    std::printf("wrote %s/vlod.md in %.0f s\n", args->params.out_dir.c_str(), summary["seconds"].get<double>());
  });
}

}  // namespace cellwalk::app
