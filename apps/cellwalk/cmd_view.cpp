// cellwalk view: the interactive viewer in a window.
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/strategy/strategy.hpp"
#include "cellwalk/runtime/viewer.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_view(CLI::App& root) {
  auto* cmd = root.add_subcommand("view",
                                  "Walk or fly through a scene in a window (W/A/S/D, drag to look, B bird's-eye, "
                                  "R record, F fly, Esc quit)");
  struct Args {
    std::string scene;
    ViewerOptions options;
    double budget_mib = 0;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("world", args->scene, "World file (.cww)")->required();
  cmd->add_option("--strategy", args->options.strategies,
                  "Strategy (repeat it for several: Tab switches between them): " + CLI::detail::join(strategy_names()))
      ->capture_default_str();
  cmd->add_option("--width", args->options.width, "Window width")->capture_default_str()->check(integer_in(16, 8192));
  cmd->add_option("--height", args->options.height, "Window height")->capture_default_str()->check(integer_in(16, 8192));
  cmd->add_option("--fov", args->options.fov_y_deg, "Vertical field of view, degrees")->capture_default_str()->check(number_in(1, 170));
  cmd->add_option("--record", args->options.record_file, "Record the flown path to this file from the start (R stops/starts; default file recorded.path)");
  cmd->add_option("--replay", args->options.replay_file, "Follow this path file instead of the keyboard, to its end (or --frames)");
  cmd->add_option("--frames", args->options.max_frames, "Quit after this many frames (0 = run until closed)")->capture_default_str()->check(integer_in(0, 100000000));
  cmd->add_option("--screenshot", args->options.screenshot_file, "Write the last frame to this PNG on exit");
  cmd->add_flag("--birds-eye", args->options.birds_eye, "Start in the bird's-eye view");
  cmd->add_option("--budget", args->budget_mib,
                  "Memory budget, MiB (0 = none): the strategy's store and the GPU cache, split as walk splits it")
      ->capture_default_str()->check(number_in(0, 1 << 24));
  cmd->add_flag("--json", args->json, "Print what the run showed as JSON when it ends");
  cmd->callback([args] {
    args->options.budget_bytes = static_cast<uint64_t>(args->budget_mib * 1024 * 1024);
    refuse_same_files({args->scene, args->options.replay_file}, {args->options.record_file, args->options.screenshot_file});
    World world(args->scene);
    const ViewerSummary v = run_viewer(world, args->options);
    if (args->json)
      print_json("view", {{"input", args->scene}, {"strategies", args->options.strategies}, {"frames", v.frames},
                          {"mean_frame_ms", v.mean_frame_ms}, {"worst_frame_ms", v.worst_frame_ms},
                          {"mean_objects", v.mean_objects}, {"mean_triangles", v.mean_triangles},
                          {"peak_resident_bytes", v.peak_resident_bytes}, {"screenshots", v.screenshots},
                          {"recorded", v.recorded_file.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(v.recorded_file)},
                          {"recorded_frames", v.recorded_frames}, {"stopped_by_signal", v.stopped_by_signal}});
  });
}

}  // namespace cellwalk::app
