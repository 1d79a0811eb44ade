// cellwalk bench lichiang: Li & Chiang's four cases (seed 003) on generated cities
// (experiments/lichiang/lichiang_report.hpp).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/lichiang/lichiang_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_lichiang(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand(
      "lichiang", "Li & Chiang (seed 003): the four cases (cache, prefetch) on each path kind -> <out>/lichiang.md");
  struct Args {
    LiChiangBenchParams params;
    bool json = false;
    bool no_plot = false;
  };
  auto args = std::make_shared<Args>();
  LiChiangBenchParams& p = args->params;
  cmd->add_option("--objects", p.world_objects, "Objects of each world (the seed's: 128 and 370)")->capture_default_str()->check(integer_in(1, 10000000));
  cmd->add_option("--landmark-fraction", p.landmark_fraction, "Fraction of landmark models in the cities")->capture_default_str()->check(number_in(0, 1));
  cmd->add_option("--city-seed", p.city_seed, "The cities' seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--cell-size", p.cell_size, "View cell side, metres")->capture_default_str()->check(number_in(0.1, 1e5));
  cmd->add_option("--along-margin", p.along_margin, "Sets are computed for the cells within this of a path (m)")->capture_default_str()->check(number_in(0, 1e5));
  cmd->add_option("--path", p.path_kinds, "Path kinds, one walk each")->capture_default_str()->check(session_kind_check());
  cmd->add_option("--frames", p.frames, "Frames of each path")->capture_default_str()->check(integer_in(2, 100000));
  cmd->add_option("--path-seed", p.path_seed, "The paths' seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--cache-fraction", p.cache_fractions, "The cache shares of the budget, as fractions of the world's geometry")->capture_default_str()->check(number_in(1e-6, 1));
  cmd->add_option("--storage", p.storages, "Storage the cases also run on, each world's first path: direct (page cache bypassed), slow (bypassed, with --read-latency-ms), sqlite (the object database)")->capture_default_str()->check(CLI::IsMember({"direct", "slow", "sqlite"}));
  cmd->add_option("--read-latency-ms", p.read_latency_ms, "The slow disk's wait before every read, ms")->capture_default_str()->check(number_in(0, 1000));
  cmd->add_option("--plot-fraction", p.plot_fractions, "Cache shares of the cache-size against prefetch-time plot")->capture_default_str()->check(number_in(1e-6, 1));
  cmd->add_option("--plot-tp", p.plot_tp_ms, "Allowable prefetching times t_p of that plot, ms a frame")->capture_default_str()->check(number_in(0, 1e6));
  cmd->add_flag("--no-plot", args->no_plot, "Skip the cache-size against prefetch-time plot");
  cmd->add_option("--gpu-budget", p.gpu_mib, "The renderer's buffer cache, MiB")->capture_default_str()->check(number_in(0, 65536));
  cmd->add_option("--width", p.width, "Image width")->capture_default_str()->check(integer_in(16, 4096));
  cmd->add_option("--height", p.height, "Image height")->capture_default_str()->check(integer_in(16, 4096));
  cmd->add_option("--threads", p.threads, "Precompute threads (0: all cores)")->capture_default_str()->check(integer_in(0, 1024));
  cmd->add_option("--out", p.out_dir, "Directory of the report (lichiang.md and lichiang/)")->capture_default_str();
  cmd->add_option("--work-dir", p.work_dir, "Where the worlds go (default: a temporary directory)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    if (args->no_plot) args->params.plot_fractions.clear();
    const nlohmann::ordered_json summary = run_lichiang_bench(args->params);
    if (args->json) {
      print_json("bench lichiang", summary);
      return;
    }
    std::printf("hybrid + relevance beat LRU + one-step on stalls and hit ratio on %d of %d paths\nwrote %s/lichiang.md\n",
                summary["beaten"].get<int>(), summary["compared"].get<int>(), args->params.out_dir.c_str());
  });
}

}  // namespace cellwalk::app
