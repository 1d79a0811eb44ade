// cellwalk stratify: the stratified rendering system's commands (seed 002, Xiong 1996).
//   plan   viewcell and box sizing, cell counts and the multi-shell analysis (digest 002 §3.3–§3.11)
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/sizing.hpp"
#include "checks.hpp"
#include "commands.hpp"

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

void register_plan(CLI::App& stratify) {
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
    if (o->json) std::printf("%s\n", j.dump(2).c_str());
    else print_plan(j);
  });
}

}  // namespace

void register_stratify(CLI::App& root) {
  auto* cmd = root.add_subcommand("stratify", "Stratified rendering (seed 002): near polygons, far field on box faces");
  cmd->require_subcommand(1);
  register_plan(*cmd);
}

}  // namespace cellwalk::app
