// cellwalk compare: fidelity of one strategy or several against ground truth along a path.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

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
  std::string captured;  // a folder of frames drawn elsewhere (web/test/walk.mjs)
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

std::string read_file(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) fail(file, "cannot be read; rerun web/test/walk.mjs to capture the frames");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// What web/test/walk.mjs wrote: captured.json (the size, the frames) and each frame's images.
std::vector<CapturedFrame> read_captured(const std::string& folder, int& width, int& height) {
  const std::string manifest = folder + "/captured.json";
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(read_file(manifest));
    width = j.at("width").get<int>();
    height = j.at("height").get<int>();
  } catch (const nlohmann::json::exception& e) {
    fail(manifest, std::string("not a capture manifest (") + e.what() + "); rerun web/test/walk.mjs");
  }
  if (width < 16 || height < 16 || width > 8192 || height > 8192) fail(manifest, "an image size out of 16..8192");
  const size_t pixels = size_t(width) * size_t(height);
  auto load = [&](const std::string& file, void* out) {
    const std::string bytes = read_file(file);
    if (bytes.size() != pixels * 4)
      fail(file, std::to_string(bytes.size()) + " bytes where a " + std::to_string(width) + " × " + std::to_string(height) +
                     " image has " + std::to_string(pixels * 4) + "; rerun web/test/walk.mjs");
    std::memcpy(out, bytes.data(), bytes.size());
  };
  std::vector<CapturedFrame> frames;
  for (const auto& index : j.value("frames", nlohmann::json::array())) {
    if (!index.is_number_integer()) fail(manifest, "a frame index that is not an integer");
    CapturedFrame c;
    c.frame = index.get<int>();
    c.color = {width, height, std::vector<uint8_t>(pixels * 4)};
    c.ids = {width, height, std::vector<uint32_t>(pixels)};
    const std::string stem = folder + "/frame" + std::to_string(c.frame);
    load(stem + ".rgba", c.color.rgba.data());
    load(stem + ".ids", c.ids.ids.data());
    frames.push_back(std::move(c));
  }
  if (frames.empty()) fail(manifest, "no captured frames; rerun web/test/walk.mjs with --every");
  return frames;
}

NamedFidelity compare_captured_run(CompareArgs& args, const World& world, const CameraPath& path) {
  const std::vector<CapturedFrame> captured = read_captured(args.captured, args.lens.width, args.lens.height);
  auto truth = make_strategy("ground-truth", world, {});
  RenderSettings settings = args.lens.render_settings();
  fit_backdrop(settings, world.info().bounds);
  Renderer renderer(settings);
  use_world_textures(renderer, world);
  CompareOptions options = args.options;
  options.image_dir = options.max_images > 0 ? args.out : "";
  options.label = "captured";
  Progress progress("compare captured", captured.size());
  const auto frames = compare_captured(path, args.lens.lens(), captured, *truth, renderer, options,
                                       [&](size_t done, size_t) { progress.update(done); });
  progress.finish();
  const FidelitySummary summary = summarize(frames);
  write_fidelity_csv(frames, args.out + "/captured-fidelity.csv");
  write_file_atomically(args.out + "/captured-fidelity.json", labelled_json("captured", summary).dump(2) + "\n");
  return {"captured", summary};
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
  cmd->add_option("--captured", args->captured,
                  "Compare frames drawn elsewhere instead of a strategy's: a folder from web/test/walk.mjs (the browser "
                  "client), at its image size");
  cmd->callback([args] {
    args->check_strategies();
    World world(args->world, args->world_options());
    const CameraPath path = args->read_checked_path(world);
    const OutputFolder folder = args->make_output_folder();
    auto context = GlContext::headless(args->rasteriser());
    const RunBudget budget = args->run_budget(path.frames.size());
    std::vector<std::string> labels;
    std::vector<NamedFidelity> runs;
    if (!args->captured.empty())
      runs.push_back(compare_captured_run(*args, world, path));
    else
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
