// cellwalk path: generate a camera path of one session kind on a scene's navigation graph.
#include <cstdio>

#include "cellwalk/scene/path_generator.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/store/world.hpp"
#include "checks.hpp"
#include "commands.hpp"

namespace cellwalk::app {

void register_path(CLI::App& root) {
  auto* cmd = root.add_subcommand("path", "Generate a camera path that stays in a scene's streets");
  struct Args {
    std::string scene, out, kind = "normal";
    PathParams params;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("file", args->scene, "World file (.cww) or scene file (.cwscene)")->required();
  cmd->add_option("-o,--output", args->out, "Path file to write")->required();
  cmd->add_option("--kind", args->kind,
                  "Session kind: normal, slow, fast, turning, backward, back-and-forth, random")
      ->capture_default_str();
  cmd->add_option("--frames", args->params.frames, "Number of frames")->capture_default_str()->check(integer_in(1, 10000000));
  cmd->add_option("--fps", args->params.fps, "Frames per second of path time")->capture_default_str()->check(number_in(0.1, 1000));
  cmd->add_option("--seed", args->params.seed, "Random seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->callback([args] {
    refuse_same_files({args->scene}, {args->out});
    args->params.kind = parse_session_kind(args->kind);
    const SceneInfo info = is_world_file(args->scene) ? World(args->scene).info() : SceneReader(args->scene).info();
    CameraPath path = generate_path(info.nav, args->params);
    path.world = path_world(info);
    write_path(path, args->out);
    std::printf("path: %zu frames (%s, %.1f s) written to %s\n", path.frames.size(), args->kind.c_str(),
                path.frames.back().time, args->out.c_str());
  });
}

}  // namespace cellwalk::app
