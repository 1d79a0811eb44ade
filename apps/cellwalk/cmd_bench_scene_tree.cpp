// cellwalk bench scene-tree: HDoV thesis ch. 6's Table 6.1 and Figs. 6.4–6.7 (VSC and PB against
// CONV) with the fidelity of every setting; experiments/scene_tree/scene_tree_report.cpp does the work.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/scene_tree/scene_tree_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

// `command_line` gives the command as typed, recorded in the report (cmd_bench.cpp).
void register_bench_scene_tree(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand(
      "scene-tree", "Memory HDoV scene tree: VSC and PB vs CONV, speed and fidelity -> <out>/scene-tree.md");
  struct Args {
    SceneTreeBenchParams params;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  SceneTreeBenchParams& p = args->params;
  cmd->add_option("--objects", p.objects, "Objects of the generated city")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--seed", p.seed, "City and path seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--frames", p.frames, "Frames of the walk")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--fps", p.fps, "Path sampling rate (frames per second of walking)")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--cell-size", p.cell_size, "View-cell side, metres")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--dov-resolution", p.dov_resolution, "DoV cube-map face resolution (thesis: 256)")
      ->capture_default_str()
      ->check(number_in(4, 1024));
  cmd->add_option("--etas", p.etas, "VSC thresholds η")->capture_default_str()->check(number_in(0, 1e12));
  cmd->add_option("--budgets", p.budgets, "PB polygon budgets")->capture_default_str()->check(number_in(0, 1e12, true));
  cmd->add_option("--rounds", p.rounds, "Timed replays per setting (interleaved); the fastest is reported")
      ->capture_default_str()
      ->check(number_in(0, 1e12, true));
  cmd->add_option("--every", p.fidelity_every, "Compare every k-th frame with ground truth")
      ->capture_default_str()
      ->check(number_in(0, 1e12, true));
  cmd->add_option("--width", p.width, "Image width")->capture_default_str()->check(number_in(16, 8192));
  cmd->add_option("--height", p.height, "Image height")->capture_default_str()->check(number_in(16, 8192));
  cmd->add_option("--threads", p.threads, "Build and DoV threads (0 = all cores)")->capture_default_str()->check(thread_count());
  cmd->add_option("--out", p.out_dir, "Directory of the report (scene-tree.md and scene-tree/)")->capture_default_str();
  cmd->add_option("--work-dir", p.work_dir, "Where the scene, world and tree files go (default: a temporary directory)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    const nlohmann::ordered_json summary = run_scene_tree_bench(args->params);
    if (args->json) {
      print_json("bench scene-tree", summary);
      return;
    }
    for (const auto& sentence : summary["reading"]) std::printf("%s\n", sentence.get<std::string>().c_str());
    std::printf("wrote %s/scene-tree.md\n", args->params.out_dir.c_str());
  });
}

}  // namespace cellwalk::app
