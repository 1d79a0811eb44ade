// cellwalk path: generate a camera path of one session kind on a world's navigation graph, or
// on the graph of its free space the path planner makes (--planner; also when the world's own
// graph does not lie in it, as an import's loop does not).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <string>

#include "cellwalk/core/error.hpp"
#include "cellwalk/precompute/path_planner.hpp"
#include "cellwalk/scene/path_generator.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/vdr/vdr_paths.hpp"
#include "checks.hpp"
#include "commands.hpp"

namespace cellwalk::app {

// The planned free space. When the planner was not asked for (the world's own graph is
// unusable) and nothing can be walked on floors, as around a lone model without a ground, it
// flies instead, with a note; what the user asked for fails as asked.
PlannedSpace plan_or_fly(const World& world, PlannerOptions options, bool may_fly) {
  if (!may_fly || options.fly) return plan_free_space(world, options);
  try {
    return plan_free_space(world, options);
  } catch (const Error& e) {
    if (std::string(e.what()).find("no free space to walk") == std::string::npos) throw;
    std::printf("path: no floor to walk on; flying through the free space instead (--planner --fly)\n");
    options.fly = true;
    return plan_free_space(world, options);
  }
}

// The VDR thesis's camera paths (seed 004, §4.6) around the world's bounds: 1 approaches and
// scans (180 frames), 2 approaches and orbits (194) — the inspection paths for one model.
CameraPath thesis_camera_path(const SceneInfo& info, int which, double fps) {
  CameraPath out;
  const std::vector<vdr::VdrFrame> frames = vdr::thesis_path(which, info.bounds);
  for (size_t i = 0; i < frames.size(); ++i) {
    const Vec3 d = glm::normalize(frames[i].aim - frames[i].eye);
    out.frames.push_back({double(i) / fps, frames[i].eye, float(std::atan2(-d.x, -d.z) * 180 / std::numbers::pi),
                          float(std::asin(std::clamp(d.y, -1.0f, 1.0f)) * 180 / std::numbers::pi)});
  }
  return out;
}

void register_path(CLI::App& root) {
  auto* cmd = root.add_subcommand("path", "Generate a camera path in a world's streets or, planned, its free space");
  struct Args {
    std::string scene, out, kind = "normal";
    PathParams params;
    bool planner = false;
    PlannerOptions planning;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("file", args->scene, "World file (.cww) or scene file (.cwscene)")->required();
  cmd->add_option("-o,--output", args->out, "Path file to write")->required();
  cmd->add_option("--kind", args->kind,
                  "Session kind: normal, slow, fast, turning, backward, back-and-forth, random; or around the world's "
                  "bounds, the VDR thesis's paths: scan (approach, then scans up and across; 180 frames) or orbit "
                  "(approach, then orbit; 194 frames)")
      ->capture_default_str();
  cmd->add_option("--frames", args->params.frames, "Number of frames")->capture_default_str()->check(integer_in(1, 10000000));
  cmd->add_option("--fps", args->params.fps, "Frames per second of path time")->capture_default_str()->check(number_in(0.1, 1000));
  cmd->add_option("--seed", args->params.seed, "Random seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  auto* planner = cmd->add_flag("--planner", args->planner,
                                "Walk a collision-free graph of the world's free space, planned from its triangles "
                                "(world files only; the default when the world's graph does not lie in it)");
  const std::string automatic = " (default: chosen from the world's size; docs/path-planner.md)";
  cmd->add_option("--eye-height", args->planning.eye_height, "Planner: eye height above the floor, metres" + automatic)
      ->check(number_in(0, 1e6, true))->needs(planner);
  cmd->add_option("--clearance", args->planning.clearance, "Planner: least distance kept from every triangle" + automatic)
      ->check(number_in(0, 1e6, true))->needs(planner);
  cmd->add_option("--spacing", args->planning.spacing, "Planner: grid step" + automatic)
      ->check(number_in(0, 1e6, true))->needs(planner);
  cmd->add_option("--reach", args->planning.reach,
                  "Planner: leave out places farther than this from anything to see" + automatic)
      ->check(number_in(0, 1e7, true))->needs(planner);
  cmd->add_flag("--fly", args->planning.fly, "Planner: fly through the volume (a 3-D grid) instead of walking on floors")
      ->needs(planner);
  cmd->callback([args] {
    refuse_same_files({args->scene}, {args->out});
    if (args->kind == "scan" || args->kind == "orbit") {
      if (args->planner) fail("--planner", "plans street and free-space paths; scan and orbit go around the world's bounds");
      const SceneInfo info = is_world_file(args->scene) ? World(args->scene).info() : SceneReader(args->scene).info();
      CameraPath path = thesis_camera_path(info, args->kind == "scan" ? 1 : 2, args->params.fps);
      path.world = path_world(info);
      write_path(path, args->out);
      std::printf("path: %zu frames (%s, %.1f s) written to %s\n", path.frames.size(), args->kind.c_str(), path.frames.back().time,
                  args->out.c_str());
      return;
    }
    args->params.kind = parse_session_kind(args->kind);
    const bool world_file = is_world_file(args->scene);
    std::optional<World> world;
    if (world_file) world.emplace(args->scene);
    const SceneInfo info = world ? world->info() : SceneReader(args->scene).info();
    bool plan = args->planner;
    if (!plan && world && !nav_lies_in_world(*world)) {
      std::printf("path: the world's navigation graph does not lie in it; planning its free space (--planner)\n");
      plan = true;
    }
    if (plan && !world_file)
      fail(args->scene, "the planner needs the world's triangles; build the scene (cellwalk build) and plan on the world file");
    CameraPath path;
    if (plan) {
      const PlannedSpace space = plan_or_fly(*world, args->planning, !args->planner);
      const PlannerOptions& o = space.options;
      std::printf("path: planned %zu nodes, %zu edges of free space (of %llu grid points, %llu free) in %.2f s "
                  "(+%.2f s loading); eye height %.3g, clearance %.3g, spacing %.3g, reach %.3g%s\n",
                  space.nav.nodes.size(), space.nav.edges.size(), static_cast<unsigned long long>(space.candidates),
                  static_cast<unsigned long long>(space.free), space.plan_seconds, space.load_seconds, o.eye_height,
                  o.clearance, o.spacing, o.reach, o.fly ? ", flying" : "");
      path = generate_path(space.nav, args->params);
    } else {
      path = generate_path(info.nav, args->params);
    }
    path.world = path_world(info);
    write_path(path, args->out);
    std::printf("path: %zu frames (%s, %.1f s) written to %s\n", path.frames.size(), args->kind.c_str(),
                path.frames.back().time, args->out.c_str());
  });
}

}  // namespace cellwalk::app
