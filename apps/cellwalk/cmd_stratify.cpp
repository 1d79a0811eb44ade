// cellwalk stratify: the stratified rendering system's commands (seed 002, Xiong 1996).
//   plan   viewcell and box sizing, cell counts and the multi-shell analysis (digest 002 §3.3–§3.11)
//   build  viewcells, near lists and baked far faces, stored in the world (§3.1)
#include <chrono>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/bake_log.hpp"
#include "cellwalk/systems/stratified/bake_pool.hpp"
#include "cellwalk/systems/stratified/sizing.hpp"
#include "cellwalk/systems/stratified/stored_stratified.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "precompute/pvs_builder.hpp"
#include "json_output.hpp"

namespace cellwalk::app {
namespace {

using namespace cellwalk::stratified;
using Json = nlohmann::ordered_json;

double rad(double degrees) { return degrees * std::numbers::pi / 180.0; }
double deg(double radians) { return radians * 180.0 / std::numbers::pi; }
std::string metres(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g m", x);
  return text;
}

struct PlanOptions {
  std::string world;
  double alpha_deg = 10.0;
  double box = 0.0;  // 0: from the budget (Eq. 2.3)
  double length = 1000.0, width = 0.0, height = 10.0;  // width 0: = length
  HardwareBudget budget;
  std::string shells = "linear";
  double shell_factor = 0.0;  // 0: search for the best
  bool check = true;
  bool json = false;
};

// The model's extent and polygon density from a world: its ground extent (x, z), its height
// (y) and triangles over the volume they bound.
void take_world(PlanOptions& o) {
  const World world(o.world);
  const Aabb& b = world.info().bounds;
  const Vec3 size = b.size();
  if (!(size.x > 0 && size.z > 0 && size.y > 0))
    fail(o.world, "the world's bounds are flat or empty, so no viewcells can be sized for it");
  o.length = size.x;
  o.width = size.z;
  o.height = size.y;
  o.budget.density = static_cast<double>(world.triangle_count()) / (double(size.x) * size.y * size.z);
}

Json sizing_row(const char* name, double v, double b, const ModelExtent& model, const PlanOptions& o) {
  const CellCount count = count_viewcells(v, o.length, o.width, o.height);
  Json row = {{"sizing", name}, {"v", v}, {"cells", count.grid}, {"cells_by_volume", count.volume_ratio},
              {"crossings_per_s_walking", crossings_per_second(1.0, v)},
              {"crossings_per_s_driving", crossings_per_second(100 / 3.6, v)}};
  row["worst_angle_deg"] = o.check ? Json(deg(worst_case_angle(v, b, model).angle)) : Json(nullptr);
  return row;
}

Json shell_json(const PlanOptions& o, double b) {
  if (o.shells == "none") return nullptr;
  const ShellSpacing spacing = o.shells == "linear" ? ShellSpacing::kLinear : ShellSpacing::kExponential;
  const ModelExtent model{std::max(o.length, o.width), o.height};
  double f = o.shell_factor;
  ShellPlan plan;
  if (f > 0) {
    plan = multi_shell(rad(o.alpha_deg), b, f, spacing, model);
  } else {
    ShellSearch best = spacing == ShellSpacing::kLinear
                           ? best_shell_spacing(rad(o.alpha_deg), b, spacing, model, 1.05, 4.0, 0.0025)
                           : best_shell_spacing(rad(o.alpha_deg), b, spacing, model, 1.005, 1.5, 0.0005);
    f = best.f;
    plan = std::move(best.plan);
  }
  Json levels = Json::array();
  for (const Shell& s : plan.shells) levels.push_back({{"v", s.v}, {"b", s.b}, {"l", s.l}, {"cells", s.cells}});
  const ShellCosts costs = shell_costs(plan, o.length * o.width * o.height, 4, 512.0 * 512.0, 4, 1.0);
  return {{"spacing", o.shells}, {"f", f}, {"searched", o.shell_factor <= 0}, {"levels", levels},
          {"cells", plan.cells}, {"texture_bytes_uncompressed", costs.texture_bytes},
          {"update_bytes_per_m", costs.update_bytes_per_s}, {"update_per_m_as_printed", costs.update_as_printed}};
}

Json plan_json(PlanOptions o) {
  if (!o.world.empty()) take_world(o);
  if (o.width <= 0) o.width = o.length;
  Json box = {{"source", o.box > 0 ? "given" : "budget (Eq. 2.3)"}};
  double b = o.box;
  if (b <= 0) {
    const BoxSizing s = box_side_from_budget(o.budget);
    b = s.b;
    box["polygons_per_frame"] = s.polygons_per_frame;
    box["fill_per_frame"] = s.fill_per_frame;
    box["textured_pixels"] = s.textured_pixels;
    box["density"] = o.budget.density;
  }
  box["b"] = b;
  const ModelExtent model{std::max(o.length, o.width), o.height};
  if (!(b < model.length))
    fail("stratify plan", "the box (" + metres(b) + ") is not smaller than the model (" + metres(model.length) + "): every object is near, nothing is far");
  const double a = rad(o.alpha_deg);
  Json sizings = Json::array();
  sizings.push_back(sizing_row("eq22", eq22_viewcell_side(a, b, model.length), b, model, o));
  sizings.push_back(sizing_row("strict", strict_viewcell_side(a, b), b, model, o));
  if (o.check) sizings.push_back(sizing_row("numerical", viewcell_side(Sizing::kNumerical, a, b, model), b, model, o));
  return {{"alpha_deg", o.alpha_deg},
          {"model", {{"world", o.world.empty() ? Json(nullptr) : Json(o.world)}, {"x", o.length}, {"y", o.width}, {"height", o.height}}},
          {"box", box},
          {"sizings", sizings},
          {"multi_shell", shell_json(o, b)}};
}

void print_plan(const Json& j) {
  const Json& m = j["model"];
  std::printf("stratify plan: α = %g°, model %.1f × %.1f × %.1f m, box b = %.2f m (%s)\n", j["alpha_deg"].get<double>(),
              m["x"].get<double>(), m["y"].get<double>(), m["height"].get<double>(), j["box"]["b"].get<double>(),
              j["box"]["source"].get<std::string>().c_str());
  if (j["box"].contains("polygons_per_frame"))
    std::printf("  Eq. 2.3: %.0f polygons a frame at %.3g polygons/m³, %.0f of %.0f fill pixels textured\n",
                j["box"]["polygons_per_frame"].get<double>(), j["box"]["density"].get<double>(),
                j["box"]["textured_pixels"].get<double>(), j["box"]["fill_per_frame"].get<double>());
  std::printf("  %-10s %10s %14s %12s %14s %14s\n", "sizing", "v (m)", "worst angle", "cells", "by volume", "crossings/s");
  for (const Json& r : j["sizings"]) {
    const std::string worst = r["worst_angle_deg"].is_null() ? "-" : std::to_string(r["worst_angle_deg"].get<double>()).substr(0, 6) + "°";
    std::printf("  %-10s %10.3f %14s %12llu %14.4g %7.2f/%-6.2f\n", r["sizing"].get<std::string>().c_str(), r["v"].get<double>(),
                worst.c_str(), (unsigned long long)r["cells"].get<uint64_t>(), r["cells_by_volume"].get<double>(),
                r["crossings_per_s_walking"].get<double>(), r["crossings_per_s_driving"].get<double>());
  }
  std::printf("  (worst angle: the numerical checker over ray directions and cell corners; crossings/s walking 1 m/s / driving 100 km/h)\n");
  const Json& s = j["multi_shell"];
  if (s.is_null()) return;
  std::printf("  multi-shell (%s, f = %.4f%s): %llu cells\n", s["spacing"].get<std::string>().c_str(), s["f"].get<double>(),
              s["searched"].get<bool>() ? ", the fewest cells found" : "", (unsigned long long)s["cells"].get<uint64_t>());
  std::printf("    %10s %10s %10s %10s\n", "v (m)", "b (m)", "l_i (m)", "cells");
  for (auto it = s["levels"].rbegin(); it != s["levels"].rend(); ++it)
    std::printf("    %10.1f %10.1f %10.1f %10llu\n", (*it)["v"].get<double>(), (*it)["b"].get<double>(), (*it)["l"].get<double>(),
                (unsigned long long)(*it)["cells"].get<uint64_t>());
}

void register_stratify_plan(CLI::App& stratify) {
  auto* cmd = stratify.add_subcommand("plan", "Size viewcells and boxes for an angular error bound (Eqs. 2.2, 2.3, 4.1)");
  auto o = std::make_shared<PlanOptions>();
  cmd->add_option("world", o->world, "World file (.cww) to size for: its extent and polygon density (optional)");
  cmd->add_option("--alpha", o->alpha_deg, "Largest angular error of the far field, degrees")
      ->check(number_in(0, 89, true))->capture_default_str();
  cmd->add_option("--box", o->box, "Bounding box side b, metres (default: from the budget, Eq. 2.3)")
      ->check(number_in(0, 1e7, true));
  cmd->add_option("--model-length", o->length, "Model length l (x), metres; a world sets it")
      ->check(number_in(0, 1e8, true))->capture_default_str();
  cmd->add_option("--model-width", o->width, "Model width (y), metres (default: the length)")->check(number_in(0, 1e8, true));
  cmd->add_option("--model-height", o->height, "Model height, metres; a world sets it")
      ->check(number_in(0, 1e8, true))->capture_default_str();
  cmd->add_option("--triangles-per-second", o->budget.triangles_per_second, "Eq. 2.3: the polygon rate P·Hz")
      ->check(number_in(0, 1e15, true))->capture_default_str();
  cmd->add_option("--fill-per-second", o->budget.textured_fill_per_second, "Eq. 2.3: textured pixels a second")
      ->check(number_in(0, 1e15, true))->capture_default_str();
  cmd->add_option("--hz", o->budget.frame_rate, "Eq. 2.3: frame rate")->check(number_in(0, 1e4, true))->capture_default_str();
  cmd->add_option("--viewport-pixels", o->budget.viewport_pixels, "Eq. 2.3: viewport pixels")
      ->check(number_in(0, 1e9, true))->capture_default_str();
  cmd->add_option("--density", o->budget.density, "Eq. 2.3: polygons per m³; a world sets it")
      ->check(number_in(0, 1e9, true))->capture_default_str();
  cmd->add_option("--shells", o->shells, "Multi-shell spacing: linear, exponential or none")
      ->check(CLI::IsMember({"linear", "exponential", "none"}))->capture_default_str();
  cmd->add_option("--shell-factor", o->shell_factor, "Multi-shell f (default: the f with the fewest cells)")
      ->check(number_in(1, 100, true));
  cmd->add_flag("!--no-check", o->check, "Skip the numerical worst-case checker (and the numerical sizing)");
  cmd->add_flag("--json", o->json, "Machine-readable output");
  cmd->callback([o] {
    const Json j = plan_json(*o);
    if (o->json) print_json("stratify plan", j);
    else print_plan(j);
  });
}

struct BuildOptions {
  std::string world, out, along;
  float along_margin = 0.0f;
  double alpha_deg = 7.5;  // Table 6.1, config A
  double box = 330.0;      // Table 6.1
  std::string sizing = "eq22";
  int resolution = 512;
  float far_level_texels = stratified::BakeSettings{}.max_texels;
  std::string screen;  // "H[:FOV]": the resolution from the screen
  std::string shard;   // "i/N": bake shard i of N into a part file
  int threads = 0;     // bakers in this process, each with a GL context of its own; 0: one a core
  std::vector<std::string> merge;  // part files to merge into the world
  bool json = false;
};

// --screen H[:FOV]: the face resolution at which a texel covers at most a pixel of that screen.
int resolution_for_screen(const std::string& screen) {
  const size_t colon = screen.find(':');
  const auto number = [&](const std::string& text) {
    size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != text.size())
      fail("stratify build", "--screen " + screen + ": give the screen's height in pixels and, after a colon, its vertical field of view in degrees (e.g. 1080:60)");
    return value;
  };
  const double height = number(screen.substr(0, colon));
  const double fov = colon == std::string::npos ? 60.0 : number(screen.substr(colon + 1));
  if (!(height >= 1 && height <= 1e5) || height != std::floor(height))
    fail("stratify build", "--screen " + screen + ": the height must be a whole number of pixels from 1 to 100000");
  if (!(fov >= 1 && fov <= 170))
    fail("stratify build", "--screen " + screen + ": the field of view must lie between 1° and 170°");
  const int resolution = face_resolution_for_screen(int(height), rad(fov));
  if (resolution > kMaxFaceResolution)
    fail("stratify build", "--screen " + screen + " needs " + std::to_string(resolution) + "² faces, over the largest, " +
                               std::to_string(kMaxFaceResolution) + "²: give a wider field of view or --resolution");
  return resolution;
}

// v for the options, sized against the world's extent (Eq. 2.2 takes the model length l).
double build_side(const BuildOptions& o, const World& world) {
  const Vec3 size = world.info().bounds.size();
  const ModelExtent model{std::max(size.x, size.z), std::max(size.y, 1.0f)};
  const Sizing sizing = o.sizing == "strict" ? Sizing::kStrict : o.sizing == "numerical" ? Sizing::kNumerical : Sizing::kEq22;
  if (!(o.box < model.length))
    fail("stratify build", "the box (" + metres(o.box) + ") is not smaller than the world (" + metres(model.length) +
                               "): every object would be near; give a smaller --box");
  return viewcell_side(sizing, rad(o.alpha_deg), o.box, model);
}

// The viewcells of the options: the k-d cells, their near lists, those baked (--along).
Viewcells make_cells(const BuildOptions& o, const World& world, float v) {
  std::vector<Aabb> bounds(world.object_count());
  for (ObjectId id = 0; id < world.object_count(); ++id) bounds[id] = world.object(id).bounds;
  Viewcells cells = build_viewcells(default_cell_region(world.info().bounds, world.info().nav, true), v, float(o.box), bounds);
  if (!o.along.empty()) {
    const CameraPath path = read_path(o.along);
    warn_if_other_world(path, o.along, world.info(), o.world);
    cells.partition = visibility::cells_along(*cells.partition, path, o.along_margin);
  }
  return cells;
}

// What baking took: the cells baked now and resumed, their time and triangles.
struct BakeWork {
  uint64_t baked = 0, resumed = 0, triangles = 0;
  double seconds = 0;
};

// Bakes the cells of shard `shard` of `shards` that `log` does not hold yet, appending each.
BakeWork bake_into(BakeLog& log, const World& world, const Viewcells& cells, const BakeSettings& settings, float b,
                   int shard, int shards, int threads) {
  BakeWork work;
  work.resumed = log.resumed();
  std::vector<CellId> computed, todo;
  for (CellId c = 0; c < cells.partition->cell_count(); ++c)
    if (cells.partition->cell(c).computed()) computed.push_back(c);
  // Shard i takes the i-th of N equal runs of the cells to bake (in id order), so shards of a
  // run restricted by --along share its cells evenly.
  const size_t from = computed.size() * size_t(shard) / size_t(shards), to = computed.size() * size_t(shard + 1) / size_t(shards);
  for (size_t i = from; i < to; ++i)
    if (!log.part().has(computed[i])) todo.push_back(computed[i]);
  if (todo.empty()) return work;
  std::vector<BakeJob> jobs;
  for (const CellId c : todo) jobs.push_back({cells.partition->cell(c).box.center(), b, cells.near.near(c)});
  const auto start = std::chrono::steady_clock::now();
  BakePool pool(world, settings, threads, std::move(jobs));
  Progress progress("stratify bake", todo.size());
  for (const CellId c : todo) {
    log.append(c, pool.next());
    progress.update(++work.baked);
  }
  progress.finish();
  work.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  work.triangles = pool.triangles_drawn();
  return work;
}

// The parts of one run, every shard once; a cell's far field from the part that baked it.
std::vector<BakePart> read_parts(const std::vector<std::string>& files, uint64_t hash) {
  std::vector<BakePart> parts;
  std::vector<bool> seen;
  for (const std::string& file : files) {
    parts.emplace_back(file);
    const BakePart& p = parts.back();
    if (p.hash() != hash)
      fail(file, "is a part of a different bake (world, cells, α, box, resolution or levels): give --merge the parts of "
                 "one run, with the options their shards were given");
    if (seen.empty()) seen.assign(size_t(p.shards()), false);
    if (p.shards() != int(seen.size())) fail(file, "is one of " + std::to_string(p.shards()) + " shards, the others of " + std::to_string(seen.size()));
    if (seen[size_t(p.shard())]) fail(file, "repeats shard " + std::to_string(p.shard()) + "/" + std::to_string(p.shards()));
    seen[size_t(p.shard())] = true;
  }
  for (size_t i = 0; i < seen.size(); ++i)
    if (!seen[i]) fail("stratify build --merge", "shard " + std::to_string(i) + "/" + std::to_string(seen.size()) + " is missing: bake it with --shard and merge again");
  return parts;
}

void print_build(const BuildOptions& o, const std::string& out, float v, const Viewcells& cells, double cells_s,
                 const StratifiedSizes& sizes, const BakeWork& work, const std::string& part) {
  const double per_cell_ms = work.baked ? 1e3 * work.seconds / double(work.baked) : 0.0;
  const uint64_t triangles_per_cell = work.baked ? work.triangles / work.baked : 0;
  const uint64_t stored = sizes.color_bytes + sizes.id_bytes + sizes.depth_bytes;
  if (o.json) {
    const Json j = {{"output", part.empty() ? out : part}, {"alpha_deg", o.alpha_deg}, {"v", v}, {"b", o.box}, {"sizing", o.sizing},
                    {"resolution", o.resolution}, {"far_level_texels", o.far_level_texels}, {"threads", o.threads}, {"shard", o.shard.empty() ? Json(nullptr) : Json(o.shard)},
                    {"cells", cells.partition->cell_count()}, {"baked_now", work.baked}, {"resumed", work.resumed},
                    {"baked_cells", sizes.baked_cells}, {"kd_height", cells.height}, {"peak_held_ids", cells.peak_held_ids},
                    {"near_ids", sizes.near_ids}, {"near_bytes", sizes.near_bytes}, {"faces", sizes.faces},
                    {"raw_face_bytes", sizes.raw_face_bytes}, {"color_bytes", sizes.color_bytes}, {"id_bytes", sizes.id_bytes},
                    {"depth_bytes", sizes.depth_bytes}, {"cells_seconds", cells_s}, {"bake_seconds", work.seconds},
                    {"bake_ms_per_cell", per_cell_ms}, {"bake_triangles_per_cell", triangles_per_cell}};
    print_json("stratify build", j);
    return;
  }
  std::printf("stratify build: α = %g°, v = %.2f m (%s), b = %g m: %llu cells (k-d height %u); baked %llu now (%.0f ms and %llu triangles a cell), %llu resumed\n",
              o.alpha_deg, v, o.sizing.c_str(), o.box, (unsigned long long)cells.partition->cell_count(), cells.height,
              (unsigned long long)work.baked, per_cell_ms, (unsigned long long)triangles_per_cell, (unsigned long long)work.resumed);
  if (!part.empty()) {
    std::printf("  wrote shard %s to %s: merge every shard with --merge\n", o.shard.c_str(), part.c_str());
    return;
  }
  std::printf("  near lists: %.1f objects a cell on average, %llu bytes; built in %.2f s (peak %llu ids held)\n",
              sizes.cells ? double(sizes.near_ids) / sizes.cells : 0.0, (unsigned long long)sizes.near_bytes, cells_s,
              (unsigned long long)cells.peak_held_ids);
  std::printf("  far faces %d²: %llu cells, %llu faces, %.1f MiB stored (colour %.1f, ids %.1f, depth %.1f) of %.1f MiB raw\n",
              o.resolution, (unsigned long long)sizes.baked_cells, (unsigned long long)sizes.faces, stored / 1048576.0,
              sizes.color_bytes / 1048576.0, sizes.id_bytes / 1048576.0, sizes.depth_bytes / 1048576.0,
              sizes.raw_face_bytes / 1048576.0);
  std::printf("  wrote %s\n", out.c_str());
}

// Bakes into a checkpoint (resumed when one of this run is there), or shard i of N into a part
// file, or merges the parts; then, but for a shard, writes the world with the far faces read
// back from the checkpoint or the parts, and removes the checkpoint.
void run_build(BuildOptions o) {
  if (!o.screen.empty()) o.resolution = resolution_for_screen(o.screen);
  // One a core, at most 8: each thread holds a GL context and its caches (llvmpipe's own threads
  // already spread each draw over the cores).
  if (o.threads == 0) o.threads = int(std::clamp(std::thread::hardware_concurrency(), 1u, 8u));
  int shard = 0, shards = 1;
  if (!o.shard.empty()) visibility::parse_shard(o.shard, shard, shards);
  const std::string out = o.out.empty() ? o.world : o.out;
  const std::string part = o.shard.empty() ? "" : o.out.empty() ? o.world + ".stratify-part-" + std::to_string(shard) + "-of-" + std::to_string(shards) : o.out;
  refuse_same_files(o.merge, {part.empty() ? out : part});
  const World world(o.world);
  const float v = float(build_side(o, world));
  const auto start = std::chrono::steady_clock::now();
  const Viewcells cells = make_cells(o, world, v);
  const double cells_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const StratifiedParams params{float(rad(o.alpha_deg)), v, float(o.box), o.sizing, o.resolution, o.far_level_texels};
  const BakeSettings settings{.resolution = o.resolution, .max_texels = o.far_level_texels};
  const uint64_t hash = bake_run_hash(world, cells, params, settings);
  BakeWork work;
  std::vector<BakePart> parts;
  std::optional<BakeLog> log;
  if (o.merge.empty()) {
    log.emplace(part.empty() ? out + ".stratify-checkpoint" : part, hash, shard, shards);
    work = bake_into(*log, world, cells, settings, float(o.box), shard, shards, o.threads);
    if (!part.empty()) return print_build(o, out, v, cells, cells_s, {}, work, part);
    parts.push_back(log->part());
  } else {
    parts = read_parts(o.merge, hash);
  }
  const StratifiedSizes sizes = write_world_with_stratified(world, out, cells, params, [&](CellId c) {
    for (const BakePart& p : parts)
      if (p.has(c)) return p.record(c, float(o.box), o.resolution, world.object_count());
    fail("stratify build --merge", "cell " + std::to_string(c) + " is in no part: the parts are of a shorter run; bake again");
  });
  if (log) {
    const std::string checkpoint = log->part().path();
    log.reset();
    std::filesystem::remove(checkpoint);
  }
  print_build(o, out, v, cells, cells_s, sizes, work, "");
}

void register_stratify_build(CLI::App& stratify) {
  auto* cmd = stratify.add_subcommand("build", "Make the viewcells, near lists and far faces of a world (stored in it)");
  auto o = std::make_shared<BuildOptions>();
  cmd->add_option("world", o->world, "World file (.cww)")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o->out, "Output world file (default: rewrite the input in place, atomically); with --shard, the part file");
  cmd->add_option("--alpha", o->alpha_deg, "Largest angular error of the far field, degrees")
      ->check(number_in(0, 89, true))->capture_default_str();
  cmd->add_option("--box", o->box, "Bounding box side b, metres")->check(number_in(0, 1e7, true))->capture_default_str();
  cmd->add_option("--sizing", o->sizing, "How v follows from α and b: eq22 (the thesis), strict or numerical")
      ->check(CLI::IsMember({"eq22", "strict", "numerical"}))->capture_default_str();
  auto* resolution = cmd->add_option("--resolution", o->resolution, "Texels per face side")
      ->check(CLI::Range(1, kMaxFaceResolution))->capture_default_str();
  cmd->add_option("--screen", o->screen,
                  "Derive --resolution from a screen H[:FOV] (pixels high, vertical field in degrees, default 60): texels as dense as its pixels at the view centre")
      ->excludes(resolution);
  cmd->add_option("--far-level-texels", o->far_level_texels,
                  "Far objects are baked at the coarsest level whose error covers under this many texels (0: full detail, as the thesis)")
      ->check(number_in(0, 1e3))->capture_default_str();
  auto* along = cmd->add_option("--along", o->along, "Bake only the cells near this camera path (cellwalk path); the others are stored as skipped")
      ->check(CLI::ExistingFile);
  cmd->add_option("--along-margin", o->along_margin, "--along: metres around the path whose cells are baked")
      ->check(number_in(0, 1e6))->capture_default_str()->needs(along);
  auto* shard = cmd->add_option("--shard", o->shard, "Bake only shard i of N (equal runs of the cells to bake) into a part file (i/N; -o names it); a killed run resumes");
  auto* merge = cmd->add_option("--merge", o->merge, "Merge the part files of every shard into the world (give the shards' options)")
      ->expected(1, -1)->check(CLI::ExistingFile);
  shard->excludes(merge);
  cmd->add_option("--threads", o->threads, "Bake on this many threads, each with a GL context of its own (the same bytes as one); 0: one a core, at most 8")
      ->check(CLI::Range(0, 64))->capture_default_str()->excludes(merge);
  cmd->add_flag("--json", o->json, "Machine-readable output");
  cmd->callback([o] { run_build(*o); });
}

}  // namespace

void register_stratify(CLI::App& root) {
  auto* cmd = root.add_subcommand("stratify", "Stratified rendering (seed 002): near polygons, far field on box faces");
  cmd->require_subcommand(1);
  register_stratify_plan(*cmd);
  register_stratify_build(*cmd);
}

}  // namespace cellwalk::app
