// cellwalk compare: fidelity of one strategy or several against ground truth along a path.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/metrics/fidelity.hpp"
#include "cellwalk/metrics/walk_summary.hpp"
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

struct CompareArgs : ReplayOptions {
  CompareOptions options;
};

struct NamedFidelity {
  std::string strategy;
  FidelitySummary summary;
};

// The summary as JSON, led by the run's label.
nlohmann::ordered_json labelled_json(const std::string& label, const FidelitySummary& summary) {
  nlohmann::ordered_json one = {{"strategy", label}};
  one.update(nlohmann::ordered_json::parse(to_json(summary)));
  return one;
}

std::string psnr_text(double db) { return std::isfinite(db) ? bench::fixed(db, 1) : "inf (identical)"; }

// A pixel error over the frames, with the share of frames above 1 px: "3.16 (12 %)".
std::string pixel_error_text(double px, double frames_over_1px) {
  return bench::fixed(px, 2) + " (" + bench::fixed(100 * frames_over_1px, 0) + " %)";
}

NamedFidelity compare_one(const CompareArgs& args, const World& world, const CameraPath& path,
                          const RunBudget& budget, const std::string& given, std::vector<std::string>& labels) {
  ReplayOptions::Run run = args.make_run(given, world, budget, labels);
  const std::string& label = run.label;
  const std::unique_ptr<Strategy> strategy = std::move(run.strategy);
  // The ground truth is outside the budget: it holds every object it draws (`walk` is the
  // command whose process stays within --budget).
  auto truth = make_strategy("ground-truth", world, {});
  RenderSettings settings = args.render_settings(budget);
  fit_backdrop(settings, world.info().bounds);
  Renderer renderer(settings);
  use_world_textures(renderer, world);
  CompareOptions options = args.options;
  options.image_dir = options.max_images > 0 ? args.out : "";
  options.label = label;
  Progress progress("compare " + label, path.frames.size());
  auto frames = compare(path, args.lens.lens(), *strategy, *truth, renderer, options,
                        [&](size_t done, size_t) { progress.update(done); });
  progress.finish();
  const FidelitySummary summary = summarize(frames);
  const std::string stem = args.out + "/" + label + "-fidelity";
  write_fidelity_csv(frames, stem + ".csv");
  write_file_atomically(stem + ".json", labelled_json(label, summary).dump(2) + "\n");
  if (!args.json)
    std::printf("compare %s: %zu frames, differing pixels mean %.4f%% (max %.4f%%), PSNR %s dB,\n"
                "  visible objects missed %llu of %llu (recall %.4f; drawn but covering no pixel: %llu;\n"
                "  the largest covered %llu pixels of truth),\n"
                "  pixel error max %.2f px, p99.9 %.2f px (frames over 1 px: %.1f%%, %.1f%%);\n"
                "  wrote %s.csv\n",
                label.c_str(), summary.frames, 100 * summary.mean_differing_fraction,
                100 * summary.max_differing_fraction, psnr_text(summary.mean_psnr_db).c_str(),
                (unsigned long long)summary.missed_objects, (unsigned long long)summary.visible_objects,
                summary.recall, (unsigned long long)summary.missed_drawn,
                (unsigned long long)summary.largest_missed_pixels, summary.max_pixel_error_px, summary.max_pixel_error_p999_px,
                100 * summary.pixel_error_over_1px_fraction,
                100 * summary.pixel_error_p999_over_1px_fraction, stem.c_str());
  return {label, summary};
}

std::string comparison_table(const std::vector<NamedFidelity>& runs) {
  bench::Table rows;
  for (const auto& [name, s] : runs)
    rows.push_back({name, std::to_string(s.frames), bench::fixed(100 * s.mean_differing_fraction, 3),
                    bench::fixed(100 * s.max_differing_fraction, 3), psnr_text(s.mean_psnr_db),
                    std::to_string(s.missed_objects) + " of " + std::to_string(s.visible_objects),
                    bench::fixed(s.recall, 4), std::to_string(s.missed_drawn) + " (largest " + std::to_string(s.largest_missed_pixels) + " px)",
                    pixel_error_text(s.max_pixel_error_px, s.pixel_error_over_1px_fraction),
                    pixel_error_text(s.max_pixel_error_p999_px, s.pixel_error_p999_over_1px_fraction)});
  return bench::md_table({"strategy", "frames compared", "differing pixels mean %", "max %", "PSNR dB",
                          "visible objects missed", "recall", "of the missed, drawn (largest in truth)", "pixel error max px (frames > 1 px)",
                          "p99.9 px (frames > 1 px)"},
                         rows);
}

}  // namespace

void register_compare(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "compare", "Render every k-th frame with one strategy or several and with ground truth; report the differences");
  auto args = std::make_shared<CompareArgs>();
  args->add_to(*cmd, "out/compare");
  cmd->add_option("--every", args->options.every, "Compare every k-th frame")->capture_default_str()->check(integer_in(1, 10000000));
  cmd->add_option("--images", args->options.max_images, "Write truth/test/difference PNGs of this many frames")->capture_default_str()->check(integer_in(0, 100000));
  cmd->callback([args] {
    args->check_strategies();
    World world(args->world, args->world_options());
    const CameraPath path = args->read_checked_path(world);
    const OutputFolder folder = args->make_output_folder();
    auto context = GlContext::headless(args->rasteriser());
    const RunBudget budget = args->run_budget(path.frames.size());
    std::vector<std::string> labels;
    std::vector<NamedFidelity> runs;
    for (const std::string& given : args->strategies)
      runs.push_back(compare_one(*args, world, path, budget, given, labels));
    if (args->json) {
      nlohmann::ordered_json all = nlohmann::ordered_json::array();
      for (const auto& run : runs) all.push_back(labelled_json(run.strategy, run.summary));
      print_json("compare", {{"input", args->world}, {"path", args->path}, {"output", args->out}, {"runs", all}});
    }
    const std::string table = comparison_table(runs);
    write_file_atomically(args->out + "/compare.md", table);
    if (!args->json) std::printf("\n%s\nwrote %s/compare.md\n", table.c_str(), args->out.c_str());
  });
}

}  // namespace cellwalk::app
