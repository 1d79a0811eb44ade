// cellwalk walk: replay a path headless with one strategy or several side by side; per-frame
// CSV and summary JSON per strategy, and a table comparing them.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/process_memory.hpp"
#include "cellwalk/metrics/walk_summary.hpp"
#include "cellwalk/runtime/run_budget.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/store/world.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"
#include "replay_options.hpp"
#include "json_output.hpp"

namespace cellwalk::app {
namespace {

// One strategy over the path, with a renderer of its own so no strategy inherits another's
// GPU buffers. The process's peak is measured from the strategy's construction to its release.
WalkSummary walk_one(const ReplayOptions& args, const World& world, const CameraPath& path, const RunBudget& budget,
                     uint64_t baseline, const std::string& given, std::vector<std::string>& labels) {
  reset_peak_rss();
  RenderSettings settings = args.render_settings(budget);
  fit_backdrop(settings, world.info().bounds);
  Renderer renderer(settings);
  use_world_textures(renderer, world);
  ReplayOptions::Run run = args.make_run(given, world, budget, labels);
  const std::string& label = run.label;
  const std::unique_ptr<Strategy> strategy = std::move(run.strategy);
  Progress progress("walk " + label, path.frames.size());
  // A budget counts live bytes: what a frame freed goes back to the kernel before the next one.
  const bool budgeted = budget.total_bytes > 0;
  auto frames = walk(path, args.lens.lens(), *strategy, renderer, [&](size_t done, size_t) {
    if (budgeted) return_freed_heap();
    progress.update(done);
  });
  progress.finish();
  WalkSummary summary = summarize(label, frames);
  summary.peak_resident_bytes = std::max(summary.peak_resident_bytes, strategy->peak_resident_bytes());
  summary.budget_bytes = budget.total_bytes;
  summary.strategy_budget_bytes = budget.strategy_bytes;
  summary.gpu_budget_bytes = renderer.settings().gpu_budget_bytes;
  summary.baseline_rss_bytes = baseline;
  summary.peak_rss_bytes = peak_rss_bytes();
  summary.strategy_counters = strategy->walk_counters();
  const std::string stem = args.out + "/" + label;
  write_frames_csv(frames, stem + ".csv");
  write_summary_json(summary, stem + ".json");
  if (!args.json)
    std::printf("walk %s: %zu frames, frame time mean %.2f ms (sd %.2f, p95 %.2f), %.0f triangles/frame,\n"
                "  split query %.2f / io %.2f / decode %.2f / render %.2f ms, %.1f MiB read, peak resident %.1f MiB%s\n"
                "  process peak %.1f MiB over a baseline of %.1f MiB; wrote %s.csv and %s.json\n",
                summary.strategy.c_str(), summary.frames, summary.mean_ms, summary.stddev_ms, summary.p95_ms,
                summary.frames ? double(summary.total_triangles) / summary.frames : 0.0, summary.mean_query_ms,
                summary.mean_io_ms, summary.mean_decode_ms, summary.mean_render_ms,
                summary.total_bytes_read / 1048576.0, summary.peak_resident_bytes / 1048576.0,
                summary.budget_bytes ? (" (budget " + bench::fixed(summary.budget_bytes / 1048576.0, 1) + " MiB)").c_str() : "",
                summary.peak_rss_bytes / 1048576.0, summary.baseline_rss_bytes / 1048576.0, stem.c_str(), stem.c_str());
  if (!args.json && !summary.strategy_counters.empty()) {
    std::string line = "  " + label + ":";
    for (const auto& [name, value] : summary.strategy_counters) line += " " + name + " " + bench::fixed(value, value == std::floor(value) ? 0 : 1) + ",";
    line.back() = '\n';
    std::fputs(line.c_str(), stdout);
  }
  return summary;
}

// The strategies side by side, each frame time also as a speed-up over the first strategy's.
std::string comparison_table(const std::vector<WalkSummary>& runs) {
  bench::Table rows;
  for (const WalkSummary& s : runs)
    rows.push_back({s.strategy, bench::fixed(s.mean_ms, 1), bench::fixed(s.stddev_ms, 1), bench::fixed(s.p95_ms, 1),
                    bench::fixed(s.mean_ms > 0 ? runs.front().mean_ms / s.mean_ms : 0.0, 2) + "×",
                    bench::fixed(s.frames ? double(s.total_triangles) / s.frames : 0.0, 0),
                    bench::fixed(s.total_bytes_read / 1048576.0, 1), bench::fixed(s.peak_resident_bytes / 1048576.0, 1),
                    std::to_string(s.stalls)});
  return bench::md_table({"strategy", "frame ms mean", "sd", "p95", "speed-up vs " + runs.front().strategy,
                          "triangles/frame", "MiB read", "peak resident MiB", "stalls"},
                         rows);
}

}  // namespace

void register_walk(CLI::App& root) {
  auto* cmd = root.add_subcommand("walk", "Replay a camera path with one strategy or several and measure every frame");
  auto args = std::make_shared<ReplayOptions>();
  args->add_to(*cmd, "out/walk");
  cmd->callback([args] {
    args->check_strategies();
    args->lens.check();
    refuse_same_files({args->world, args->path}, {args->out});
    const OutputFolder folder = args->make_output_folder();
    // The baseline is measured before the world and the path are read: they are charged.
    auto context = GlContext::headless(args->rasteriser());
    const uint64_t baseline = measure_baseline(args->lens.render_settings());
    const World world(args->world, args->world_options());
    const CameraPath path = args->read_checked_path(world);
    const RunBudget budget = args->run_budget(path.frames.size());
    std::vector<std::string> labels;
    std::vector<WalkSummary> runs;
    for (const std::string& given : args->strategies)
      runs.push_back(walk_one(*args, world, path, budget, baseline, given, labels));
    if (args->json) {
      nlohmann::ordered_json all = nlohmann::ordered_json::array();
      for (const WalkSummary& s : runs) all.push_back(nlohmann::ordered_json::parse(to_json(s)));
      print_json("walk", {{"input", args->world}, {"path", args->path}, {"output", args->out}, {"runs", all}});
    }
    const std::string table = comparison_table(runs);
    write_file_atomically(args->out + "/walk.md", table);
    if (!args->json) std::printf("\n%s\nwrote %s/walk.md\n", table.c_str(), args->out.c_str());
  });
}

}  // namespace cellwalk::app
