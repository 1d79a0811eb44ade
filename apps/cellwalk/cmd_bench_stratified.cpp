// cellwalk bench stratified: the stratified thesis's experiments (seed 002 §6) on its random
// city (experiments/stratified/stratified_report.hpp).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cellwalk/systems/stratified/far_field.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "experiments/stratified/stratified_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_stratified(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand(
      "stratified", "Stratified rendering (seed 002): Table 6.1, frame times, fidelity and the far field's angle -> <out>/stratified.md");
  struct Args {
    StratifiedBenchParams params;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  StratifiedBenchParams& p = args->params;
  cmd->add_option("--blocks-x", p.city.blocks_x, "City blocks along x (10: ~1 km)")->capture_default_str()->check(integer_in(1, 1000));
  cmd->add_option("--blocks-z", p.city.blocks_z, "City blocks along z (13: ~1 km)")->capture_default_str()->check(integer_in(1, 1000));
  cmd->add_option("--max-height", p.city.max_height, "Tallest building, metres")->capture_default_str()->check(number_in(1, 1000));
  cmd->add_option("--city-seed", p.city.seed, "The city's seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--alpha", p.alphas_deg, "The angular error bounds, degrees (Table 6.1: 7.5 and 1)")->capture_default_str()->check(number_in(0, 89, true));
  cmd->add_option("--box", p.box, "Bounding box side b, metres")->capture_default_str()->check(number_in(0, 1e6, true));
  cmd->add_option("--resolution", p.resolution, "Texels per face side")->capture_default_str()->check(integer_in(1, stratified::kMaxFaceResolution));
  cmd->add_option("--path", p.path_kind, "Path kind (normal, fast, ...)")->capture_default_str()->check(session_kind_check());
  cmd->add_option("--frames", p.frames, "Frames of the path")->capture_default_str()->check(integer_in(2, 100000));
  cmd->add_option("--path-seed", p.path_seeds, "The paths' seeds, one path each")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--along-margin", p.along_margin, "Cells within this of the path are baked (m)")->capture_default_str()->check(number_in(0, 1e5));
  cmd->add_option("--bake-all-up-to", p.bake_all_up_to, "Bake every cell of an α with at most this many cells (measured); more: only along the paths (projected)")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--bake-threads", p.bake_threads, "Bake on this many threads")->capture_default_str()->check(integer_in(1, 64));
  cmd->add_option("--fade", p.fade_frames, "Also walk stratified:fade=N (the cross-fade at crossings) at every α; 0: not")->capture_default_str()->check(integer_in(0, 60));
  cmd->add_option("--far-level-texels", p.far_level_texels, "Far objects baked at the coarsest level whose error covers under this many texels (0: full detail)")->capture_default_str()->check(number_in(0, 1e3));
  auto* scale = cmd->add_option("--scale-blocks", p.scale_blocks, "Also walk a city of N x N blocks (63: about 10^7 triangles) against brute and --scale-strategy; 0: none")->capture_default_str()->check(integer_in(0, 1000));
  cmd->add_option("--scale-path", p.scale_path_kind, "Path kind at city scale")->capture_default_str()->check(session_kind_check())->needs(scale);
  cmd->add_option("--scale-frames", p.scale_frames, "Frames of the city-scale path")->capture_default_str()->check(integer_in(2, 100000))->needs(scale);
  cmd->add_option("--scale-others-every", p.scale_others_every, "At city scale, brute and the other strategies draw every k-th frame")->capture_default_str()->check(integer_in(1, 100000))->needs(scale);
  cmd->add_option("--scale-fidelity-every", p.scale_fidelity_every, "At city scale, compare every k-th frame with ground truth")->capture_default_str()->check(integer_in(1, 100000))->needs(scale);
  cmd->add_option("--scale-strategy", p.scale_strategies, "Strategies walked beside brute and stratified at city scale")->capture_default_str()->needs(scale);
  cmd->add_option("--width", p.width, "Image width")->capture_default_str()->check(integer_in(16, 4096));
  cmd->add_option("--height", p.height, "Image height")->capture_default_str()->check(integer_in(16, 4096));
  cmd->add_option("--fov", p.fov_deg, "Vertical field of view, degrees")->capture_default_str()->check(number_in(1, 170));
  cmd->add_option("--fidelity-every", p.fidelity_every, "Compare every k-th frame with ground truth")->capture_default_str()->check(integer_in(1, 100000));
  cmd->add_option("--images", p.images, "Frames whose images are written")->capture_default_str()->check(integer_in(0, 1000));
  cmd->add_option("--out", p.out_dir, "Directory of the report (stratified.md and stratified/)")->capture_default_str();
  cmd->add_option("--work-dir", p.work_dir, "Where the worlds go (default: a temporary directory)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    const nlohmann::ordered_json summary = run_stratified_bench(args->params);
    if (args->json) {
      print_json("bench stratified", summary);
      return;
    }
    nlohmann::ordered_json runs = summary["paths"];
    if (summary.contains("scale")) runs["scale"] = summary["scale"]["walks"];
    for (const auto& [seed, walks] : runs.items())
      for (const auto& [name, s] : walks.items())
        std::printf("path %-4s %-28s %8.2f ms a frame (%.2f x brute), %llu stall frames, far angle max %.2f°\n", seed.c_str(),
                    name.c_str(), s["frame_ms"].get<double>(), s["speedup"].get<double>(),
                    (unsigned long long)s["stall_frames"].get<uint64_t>(), s["max_far_angle_deg"].get<double>());
    std::printf("wrote %s/stratified.md\n", args->params.out_dir.c_str());
  });
}

}  // namespace cellwalk::app
