// cellwalk walk: replay a path headless with one strategy; per-frame CSV and summary JSON.
#include <cstdio>
#include <filesystem>

#include "cellwalk/world.hpp"
#include "cellwalk/walk.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "replay_options.hpp"

namespace cellwalk::app {

void register_walk(CLI::App& root) {
  auto* cmd = root.add_subcommand("walk", "Replay a camera path with one strategy and measure every frame");
  auto args = std::make_shared<ReplayOptions>();
  args->add_to(*cmd, "out/walk");
  cmd->callback([args] {
    World world(args->world);
    CameraPath path = read_path(args->path);
    args->make_output_folder();
    const StrategyOptions options = args->strategy_options();
    auto strategy = make_strategy(args->strategy, world, options);
    auto context = GlContext::headless();
    Renderer renderer(args->lens.render_settings());
    Progress progress("walk " + args->strategy, path.frames.size());
    auto frames = walk(path, args->lens.lens(), *strategy, renderer,
                       [&](size_t done, size_t) { progress.update(done); });
    progress.finish();
    WalkSummary summary = summarize(strategy->name(), frames);
    summary.peak_resident_bytes = std::max(summary.peak_resident_bytes, strategy->peak_resident_bytes());
    const std::string stem = args->out + "/" + strategy->name();
    write_frames_csv(frames, stem + ".csv");
    write_summary_json(summary, stem + ".json");
    if (args->json) {
      std::printf("%s\n", to_json(summary).c_str());
      return;
    }
    std::printf("walk %s: %zu frames, frame time mean %.2f ms (sd %.2f, p95 %.2f), %.0f triangles/frame,\n"
                "  split query %.2f / io %.2f / decode %.2f / render %.2f ms, %.1f MiB read, peak resident %.1f MiB%s\n"
                "  wrote %s.csv and %s.json\n",
                summary.strategy.c_str(), summary.frames, summary.mean_ms, summary.stddev_ms, summary.p95_ms,
                summary.frames ? double(summary.total_triangles) / summary.frames : 0.0, summary.mean_query_ms,
                summary.mean_io_ms, summary.mean_decode_ms, summary.mean_render_ms,
                summary.total_bytes_read / 1048576.0, summary.peak_resident_bytes / 1048576.0,
                options.memory_budget_bytes ? (" (budget " + std::to_string(options.memory_budget_bytes >> 20) + " MiB)").c_str() : "",
                stem.c_str(),
                stem.c_str());
  });
}

}  // namespace cellwalk::app
