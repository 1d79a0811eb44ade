// cellwalk bench visual: HDoV thesis §5.8 reproduced (experiments/visual/visual_report.hpp).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/visual/visual_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_visual(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand("visual", "VISUAL (HDoV thesis ch. 5): Table 5.2, Exps. 1-3, Fig. 5.23 -> <out>/visual.md");
  struct Args {
    VisualBenchParams params;
    std::string dov_cubes = dov_cubes_name(DovCubes::kRays);
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  VisualBenchParams& p = args->params;
  cmd->add_option("--objects", p.objects, "Objects of the city")->capture_default_str()->check(number_in(50, 1000000));
  cmd->add_option("--cells", p.cells_per_side, "View cells per side of the grid")->capture_default_str()->check(number_in(2, 256));
  cmd->add_option("--dov-resolution", p.dov_resolution, "DoV cube-map face resolution (thesis: 256)")->capture_default_str()->check(number_in(4, 1024));
  cmd->add_option("--dov-cubes", args->dov_cubes, "DoV cube maps by rays or exact (GL at level 0, the reference)")->capture_default_str();
  cmd->add_option("--fanout", p.fanout, "HDoV-tree fan-out M")->capture_default_str()->check(number_in(4, 140));
  cmd->add_option("--queries", p.queries, "Queries per Exp. 1/2 run")->capture_default_str()->check(number_in(1, 1000000));
  cmd->add_option("--frames", p.frames, "Frames of the Exp. 3 session")->capture_default_str()->check(number_in(2, 100000));
  cmd->add_option("--walk-cell-size", p.walk_cell_size, "Exp. 3: side of the view cells along the path, m")->capture_default_str()->check(number_in(0.5, 1000.0));
  cmd->add_option("--fidelity-every", p.fidelity_every, "Exp. 3: compare every k-th frame with ground truth")->capture_default_str()->check(number_in(1, 100000));
  cmd->add_option("--width", p.width, "Exp. 3 fidelity image width")->capture_default_str()->check(number_in(16, 4096));
  cmd->add_option("--height", p.height, "Exp. 3 fidelity image height")->capture_default_str()->check(number_in(16, 4096));
  cmd->add_option("--scale-objects", p.scale_objects, "Fig. 5.23: objects of the cities besides --objects")->capture_default_str()->check(number_in(50, 1000000));
  cmd->add_option("--scale-cells", p.scale_cells_per_side, "Fig. 5.23: cells per side of each city's central block")->capture_default_str()->check(number_in(1, 64));
  cmd->add_option("--scale-eta", p.scale_eta, "Fig. 5.23: η of the searches")->capture_default_str()->check(number_in(0.0, 1.0));
  cmd->add_option("--render-rate", p.render_mtri_per_s, "Modelled rendering rate, M triangles/s")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--cache-pages", p.cache_pages, "Node cache sizes of Exp. 1, pages")->capture_default_str()->check(number_in(0, 1e7));
  cmd->add_option("--etas", p.etas, "η values of Exp. 2")->capture_default_str()->check(number_in(0, 1));
  cmd->add_option("--walk-etas", p.walk_etas, "η values of Exp. 3")->capture_default_str()->check(number_in(0, 1));
  cmd->add_option("--seed", p.seed, "City, query and path seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--threads", p.threads, "Worker threads for DoV (0 = all cores)")->capture_default_str()->check(thread_count());
  cmd->add_option("--out", p.out_dir, "Directory of the report (visual.md and visual/)")->capture_default_str();
  cmd->add_option("--work-dir", p.work_dir, "Where the world goes (default: a temporary directory)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    args->params.dov_cubes = parse_dov_cubes(args->dov_cubes);
    const nlohmann::ordered_json summary = run_visual_bench(args->params);
    if (args->json) {
      print_json("bench visual", summary);
      return;
    }
    for (const auto& [label, w] : summary["walk"].items())
      std::printf("%-18s mean %7.2f ms  variance %8.2f  peak %6.2f MiB\n", label.c_str(), w["mean_ms"].get<double>(),
                  w["variance"].get<double>(), w["peak_bytes"].get<double>() / 1048576.0);
    std::printf("wrote %s/visual.md in %.0f s\n", args->params.out_dir.c_str(), summary["seconds"].get<double>());
  });
}

}  // namespace cellwalk::app
