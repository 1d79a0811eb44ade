// cellwalk compare: fidelity of a strategy against ground truth along a path.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cellwalk/atomic_file.hpp"
#include "cellwalk/world.hpp"
#include "cellwalk/walk.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "replay_options.hpp"

namespace cellwalk::app {

void register_compare(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "compare", "Render every k-th frame with a strategy and with ground truth; report the differences");
  struct Args : ReplayOptions {
    CompareOptions options;
  };
  auto args = std::make_shared<Args>();
  args->add_to(*cmd, "out/compare");
  cmd->add_option("--every", args->options.every, "Compare every k-th frame")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--images", args->options.max_images, "Write truth/test/difference PNGs of this many frames")->capture_default_str();
  cmd->callback([args] {
    World world(args->world);
    CameraPath path = read_path(args->path);
    auto strategy = make_strategy(args->strategy, world, args->strategy_options());
    auto truth = make_strategy("ground-truth", world, {});
    auto context = GlContext::headless();
    Renderer renderer(args->lens.render_settings());
    args->make_output_folder();
    args->options.image_dir = args->options.max_images > 0 ? args->out : "";
    Progress progress("compare " + args->strategy, path.frames.size());
    auto frames = compare(path, args->lens.lens(), *strategy, *truth, renderer, args->options,
                          [&](size_t done, size_t) { progress.update(done); });
    progress.finish();
    FidelitySummary summary = summarize(frames);
    const std::string stem = args->out + "/" + strategy->name() + "-fidelity";
    write_fidelity_csv(frames, stem + ".csv");
    write_file_atomically(stem + ".json", to_json(summary) + "\n");
    if (args->json) {
      std::printf("%s\n", to_json(summary).c_str());
      return;
    }
    std::printf("compare %s: %zu frames, differing pixels mean %.4f%% (max %.4f%%), PSNR %s dB,\n"
                "  visible objects missed %llu of %llu (recall %.4f); wrote %s.csv\n",
                strategy->name().c_str(), summary.frames, 100 * summary.mean_differing_fraction,
                100 * summary.max_differing_fraction,
                std::isfinite(summary.mean_psnr_db) ? std::to_string(summary.mean_psnr_db).c_str() : "inf (identical)",
                (unsigned long long)summary.missed_objects, (unsigned long long)summary.visible_objects,
                summary.recall, stem.c_str());
  });
}

}  // namespace cellwalk::app
