// cellwalk path: generate a camera path of one session kind on a world's navigation graph, or
// on the graph of its free space the path planner makes (--planner; also when the world's own
// graph does not lie in it, as an import's loop does not).
#include <algorithm>
#include <cmath>
#include <cctype>
#include <cstdio>
#include <cstdlib>
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
#include "json_output.hpp"

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
    std::fprintf(stderr, "path: no floor to walk on; flying through the free space instead (--planner --fly)\n");
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
    PathFrame f{double(i) / fps, frames[i].eye, 0.0f, 0.0f};
    aim_at(f, frames[i].aim);
    out.frames.push_back(f);
  }
  return out;
}

// The box of --around: an object of the world by id or name, or the whole world ("").
// `world` is null for a scene file.
Aabb inspection_target(const std::string& around, const World* world_or_null, const SceneInfo& info) {
  if (around.empty()) return info.bounds;
  if (!world_or_null) fail("--around", "needs a world file (cellwalk build) to find objects in");
  const World& world = *world_or_null;
  const std::vector<std::string> names = world.object_names();
  for (size_t id = 0; id < names.size(); ++id)
    if (names[id] == around) return world.object(ObjectId(id)).bounds;
  char* end = nullptr;
  const unsigned long long id = std::strtoull(around.c_str(), &end, 10);
  if (!around.empty() && *end == '\0' && std::isdigit(static_cast<unsigned char>(around[0])) && id < world.object_count())
    return world.object(ObjectId(id)).bounds;
  fail("--around " + around, "no object has this name or id (ids 0 to " + std::to_string(world.object_count() - 1) +
                                 "; cellwalk info --json lists the names)");
}

// --look-at: "centre" (of the world's bounds) or X,Y,Z.
Vec3 look_at_point(const std::string& look_at, const SceneInfo& info) {
  if (look_at == "centre" || look_at == "center") return info.bounds.center();
  float v[3];
  char tail = 0;
  if (std::sscanf(look_at.c_str(), "%f,%f,%f%c", &v[0], &v[1], &v[2], &tail) != 3 || !std::isfinite(v[0]) ||
      !std::isfinite(v[1]) || !std::isfinite(v[2]))
    fail("--look-at " + look_at, "give centre or a point X,Y,Z");
  return {v[0], v[1], v[2]};
}

struct PathArgs {
  std::string scene, out, kind = "normal";
  PathParams params;
  bool planner = false;
  PlannerOptions planning;
  std::string around, look_at;
  bool coverage = false;
  bool json = false;
};

// The path of the kind asked for, before --look-at. `world` is null for a scene file.
CameraPath make_path(PathArgs& args, const World* world, const SceneInfo& info) {
  if (args.kind == "inspect") {
    if (args.planner) fail("--planner", "plans street and free-space paths; inspect goes around the world or an object");
    return inspection_path(inspection_target(args.around, world, info), args.params);
  }
  if (args.kind == "scan" || args.kind == "orbit") {
    if (args.planner) fail("--planner", "plans street and free-space paths; scan and orbit go around the world's bounds");
    return thesis_camera_path(info, args.kind == "scan" ? 1 : 2, args.params.fps);
  }
  args.params.kind = parse_session_kind(args.kind);
  bool plan = args.planner;
  if (!plan && world && !nav_lies_in_world(*world)) {
    std::fprintf(stderr, "path: the world's navigation graph does not lie in it; planning its free space (--planner)\n");
    plan = true;
  }
  if (plan && !world)
    fail(args.scene, "the planner needs the world's triangles; build the scene (cellwalk build) and plan on the world file");
  if (!plan) return generate_path(info.nav, args.params);
  const PlannedSpace space = plan_or_fly(*world, args.planning, !args.planner);
  const PlannerOptions& o = space.options;
  std::fprintf(stderr, "path: planned %zu nodes, %zu edges of free space (of %llu grid points, %llu free) in %.2f s "
              "(+%.2f s loading); eye height %.3g, clearance %.3g, spacing %.3g, reach %.3g%s\n",
              space.nav.nodes.size(), space.nav.edges.size(), static_cast<unsigned long long>(space.candidates),
              static_cast<unsigned long long>(space.free), space.plan_seconds, space.load_seconds, o.eye_height,
              o.clearance, o.spacing, o.reach, o.fly ? ", flying" : "");
  return generate_path(space.nav, args.params);
}

// "in view": the world covers at least 1 % of the image (a 64-ray-wide grid).
nlohmann::ordered_json report_coverage(const World& world, const CameraPath& path, bool json) {
  const std::vector<float> coverage = view_coverage(world, path, Camera{});
  std::vector<float> sorted = coverage;
  std::sort(sorted.begin(), sorted.end());
  const size_t in_view = size_t(std::count_if(coverage.begin(), coverage.end(), [](float c) { return c >= 0.01f; }));
  const nlohmann::ordered_json j = {{"frames_in_view", in_view}, {"median_share", sorted[sorted.size() / 2]}, {"least_share", sorted.front()}};
  if (json) return j;
  std::printf("path: the world is in view (>= 1 %% of the image) on %zu of %zu frames (%.1f %%); it covers %.1f %% of "
              "the image at the median frame, %.1f %% at the least\n",
              in_view, coverage.size(), 100.0 * in_view / coverage.size(), 100.0 * sorted[sorted.size() / 2], 100.0 * sorted.front());
  return j;
}

void register_path(CLI::App& root) {
  auto* cmd = root.add_subcommand("path", "Generate a camera path in a world's streets or, planned, its free space");
  auto args = std::make_shared<PathArgs>();
  cmd->add_option("file", args->scene, "World file (.cww) or scene file (.cwscene)")->required();
  cmd->add_option("-o,--output", args->out, "Path file to write")->required();
  cmd->add_option("--kind", args->kind,
                  "Session kind: normal, slow, fast, turning, backward, back-and-forth, random; or around the world's "
                  "bounds, the VDR thesis's paths: scan (approach, then scans up and across; 180 frames) or orbit "
                  "(approach, then orbit; 194 frames); or inspect: once around the world or one object (--around), "
                  "looking at it, over --frames")
      ->capture_default_str();
  cmd->add_option("--around", args->around, "inspect: the object to go around, by name or id (default: the whole world)");
  cmd->add_option("--look-at", args->look_at,
                  "Turn every frame to look at this point: centre (of the world) or X,Y,Z (e.g. a planned flight that "
                  "keeps a model in view)");
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
  cmd->add_flag("--json", args->json, "Print what was written as JSON (the planner's notes go to standard error, as always)");
  cmd->add_flag("--coverage", args->coverage,
                "Also report how much of each frame shows the world (rays against its triangles, 60° lens, 4:3; "
                "needs a world file)");
  cmd->callback([args] {
    refuse_same_files({args->scene}, {args->out});
    if (!args->around.empty() && args->kind != "inspect") fail("--around", "goes with --kind inspect");
    if (args->coverage && !is_world_file(args->scene)) fail("--coverage", "needs a world file (cellwalk build)");
    // Opened once: the planner, --around and --coverage read the same world.
    std::optional<World> world;
    if (is_world_file(args->scene)) world.emplace(args->scene);
    const SceneInfo info = world ? world->info() : SceneReader(args->scene).info();
    const std::optional<Vec3> look_at = args->look_at.empty() ? std::nullopt : std::optional(look_at_point(args->look_at, info));
    CameraPath path = make_path(*args, world ? &*world : nullptr, info);
    if (look_at)
      for (PathFrame& f : path.frames) aim_at(f, *look_at);
    path.world = path_world(info);
    write_path(path, args->out);
    if (!args->json)
      std::printf("path: %zu frames (%s, %.1f s) written to %s\n", path.frames.size(), args->kind.c_str(),
                  path.frames.back().time, args->out.c_str());
    const nlohmann::ordered_json coverage =
        args->coverage ? report_coverage(*world, path, args->json) : nlohmann::ordered_json();
    if (args->json)
      print_json("path", {{"input", args->scene}, {"output", args->out}, {"kind", args->kind}, {"frames", path.frames.size()},
                          {"seconds", path.frames.back().time}, {"coverage", coverage}});
  });
}

}  // namespace cellwalk::app
