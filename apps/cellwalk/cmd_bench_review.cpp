// cellwalk bench review: HDoV thesis §4.4 reproduced (experiments/review/review_report.hpp).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/review/review_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_review(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand("review", "REVIEW (HDoV thesis ch. 4): Tables 4.1-4.2, Figs. 4.17-4.22 -> <out>/review.md");
  struct Args {
    ReviewBenchParams params;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  ReviewBenchParams& p = args->params;
  cmd->add_option("--objects", p.objects, "Buildings of the main city (the size sweep adds 1/4 and 1/2)")
      ->capture_default_str()->check(number_in(100, 10000000));
  cmd->add_option("--session-km", p.session_km, "Length of each session, km")->capture_default_str()->check(number_in(0.05, 1000.0));
  cmd->add_option("--path-fps", p.path_fps, "Frames per second of path time")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--speeds", p.speeds, "Session speeds, m/s: fast slow turning backward normal")->capture_default_str()->expected(5)->check(number_in(0, 100, true));
  cmd->add_option("--disk-seek-ms", p.disk_seek_ms, "Modelled disk: ms per random access")->capture_default_str()->check(number_in(0, 1e12));
  cmd->add_option("--disk-page-ms", p.disk_page_ms, "Modelled disk: ms per page transferred")->capture_default_str()->check(number_in(0, 1e12));
  cmd->add_option("--depth", p.depth, "Frustum depth, metres")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--sf", p.scale_factor, "Disk cell scale factor SF where not swept")->capture_default_str()->check(number_in(1.0, 100.0));
  cmd->add_option("--fanout", p.fanout, "R-tree fan-out M")->capture_default_str()->check(number_in(4, 1024));
  cmd->add_option("--buffer", p.buffer_mib, "Object buffer, MiB")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--cache", p.cache_mib, "Index cache, MiB")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--render-rate", p.render_mtri_per_s, "Modelled rendering rate, M triangles/s")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--ks", p.ks, "Prefetch factors k of the sweep")->capture_default_str()->check(number_in(0, 100));
  cmd->add_option("--cache-sizes", p.cache_kib, "Index cache sizes of the sweep, KiB")->capture_default_str()->check(number_in(0, 1e7));
  cmd->add_option("--cell-sizes", p.cell_sizes, "Cell sizes (SF) of the sweep")->capture_default_str()->check(number_in(1, 100));
  cmd->add_option("--fidelity-every", p.fidelity_every, "Compare every n-th frame with ground truth (0 = skip)")->capture_default_str()->check(number_in(0, 1e6));
  cmd->add_option("--seed", p.seed, "City and path seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--out", p.out_dir, "Directory of the report (review.md and review/)")->capture_default_str();
  cmd->add_option("--work-dir", p.work_dir, "Where the worlds go (default: a temporary directory)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    const nlohmann::ordered_json summary = run_review_bench(args->params);
    if (args->json) {
      print_json("bench review", summary);
      return;
    }
    for (const auto& r : summary["table41"])
      std::printf("Table 4.1 %-9s BOX %8.1f  Optimal %7.1f I/Os per query (%.1f %%), per session %.1f %%\n",
                  r["session"].get<std::string>().c_str(), r["box_ios_per_query"].get<double>(),
                  r["optimal_ios_per_query"].get<double>(), 100 * r["ratio"].get<double>(),
                  100 * r["session_ratio"].get<double>());
    std::printf("wrote %s/review.md in %.0f s\n", args->params.out_dir.c_str(), summary["seconds"].get<double>());
  });
}

}  // namespace cellwalk::app
