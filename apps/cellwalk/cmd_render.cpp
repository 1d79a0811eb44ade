// cellwalk render: one picture of a scene, from a path frame or from above.
#include <cstdio>

#include "cellwalk/core/error.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "lens_options.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_render(CLI::App& root) {
  auto* cmd = root.add_subcommand("render", "Render one view of a scene to a PNG");
  struct Args {
    std::string world, path, out, strategy = "brute";
    int frame = 0;
    LensOptions lens;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("world", args->world, "World file (.cww) from cellwalk build")->required();
  cmd->add_option("-o,--output", args->out, "PNG to write")->required();
  cmd->add_option("--path", args->path, "Camera path; without it, an overview from above the scene");
  cmd->add_option("--frame", args->frame, "Frame of the path to render")->capture_default_str()->check(integer_in(0, 10000000));
  cmd->add_option("--strategy", args->strategy, "Strategy: " + CLI::detail::join(strategy_names()))->capture_default_str();
  args->lens.add_to(*cmd);
  cmd->add_flag("--json", args->json, "Print what was drawn as JSON");
  cmd->callback([args] {
    args->lens.check();
    refuse_same_files({args->world, args->path}, {args->out});
    World world(args->world);
    Camera camera = args->lens.lens();
    if (!args->path.empty()) {
      CameraPath path = read_path(args->path);
      warn_if_other_world(path, args->path, world.info(), args->world);
      if (args->frame < 0 || size_t(args->frame) >= path.frames.size())
        fail(args->path, "frame " + std::to_string(args->frame) + " is outside the path's " +
                             std::to_string(path.frames.size()) + " frames");
      apply(path.frames[size_t(args->frame)], camera);
    } else {
      // From above one corner, looking across the scene at 35 degrees down.
      const Aabb& b = world.info().bounds;
      const float span = glm::length(b.size());
      camera.position = Vec3(b.max.x, b.max.y + 0.35f * span, b.max.z) + Vec3(0.1f, 0, 0.1f) * span;
      camera.yaw_deg = 45.0f;
      camera.pitch_deg = -35.0f;
      camera.far_plane = 4.0f * span;
      camera.near_plane = span * 1e-4f;
    }
    StrategyOptions options;
    options.viewport_height_px = float(args->lens.height);
    auto strategy = make_strategy(args->strategy, world, options);
    auto context = GlContext::headless();
    RenderSettings settings = args->lens.render_settings();
    fit_backdrop(settings, world.info().bounds);
    Renderer renderer(settings);
    use_world_textures(renderer, world);
    FrameStats stats = render_frame(*strategy, renderer, camera);
    write_png(renderer.read_color(), args->out);
    if (args->json)
      print_json("render", {{"input", args->world}, {"output", args->out}, {"strategy", strategy->name()},
                            {"objects", stats.objects}, {"triangles", stats.triangles}, {"frame_ms", stats.frame_ms}});
    else
      std::printf("render: %llu objects, %llu triangles in %.1f ms, wrote %s\n", (unsigned long long)stats.objects,
                  (unsigned long long)stats.triangles, stats.frame_ms, args->out.c_str());
  });
}

}  // namespace cellwalk::app
