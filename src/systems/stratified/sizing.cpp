// Stratified thesis §2.2–§2.4, §3.1.3, §3.2.1, §4 (digest 002 §3.2–§3.4, §3.9–§3.11): viewcell
// and bounding-box sizing, cell counts, the multi-shell analysis, and the numerical worst-case
// checker the thesis lacked [ours].
#include "cellwalk/systems/stratified/sizing.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <string>

#include "cellwalk/core/error.hpp"

namespace cellwalk::stratified {
namespace {

constexpr double kSqrt2 = std::numbers::sqrt2;

void require_positive(double x, const char* what) {
  if (!(std::isfinite(x) && x > 0)) fail("stratify plan", std::string(what) + " must be finite and positive");
}

std::string number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", x);
  return text;
}

std::string degrees(double radians) { return number(radians * 180.0 / std::numbers::pi) + "°"; }

// Eq. 2.2 written with the distance left beyond the cell, `rest` = l − v (Eq. 4.1 has l_i − v_i
// constant while v_i varies).
double eq22_with_rest(double v, double b, double rest) {
  return std::atan(kSqrt2 * rest / v) - std::atan((b - v) / (kSqrt2 * v));
}

// The smallest v in (0, b) where eq22_with_rest(v, b, rest(v)) = alpha, or NaN when there is
// none. The angle is 0 as v → 0 and rises with v, but not always up to v = b: when l is little
// more than b it peaks inside (0, b) and falls again (Fig. 2-7's l = 1100, b = 1000 peaks at
// 24.7° near v = 558 and is 8.0° at v = b). So the peak is found first (a scan, then a golden
// section), and v is bisected on the rising branch below it.
template <typename Rest>
double rising_side(double alpha, double b, Rest rest) {
  auto angle = [&](double v) { return eq22_with_rest(v, b, rest(v)); };
  constexpr int kScan = 256;
  int best = kScan;
  for (int i = 1; i <= kScan; ++i)
    if (angle(b * i / kScan) > angle(b * best / kScan)) best = i;
  double lo = b * (best - 1) / kScan, hi = b * std::min(best + 1, kScan) / kScan;
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i < 100 && hi - lo > 1e-12 * b; ++i) {
    const double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    if (angle(x1) < angle(x2)) lo = x1;
    else hi = x2;
  }
  const double peak = std::min(0.5 * (lo + hi), b);
  if (!(alpha < angle(peak))) return NAN;
  lo = 0.0, hi = peak;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * b; ++i) {
    const double mid = 0.5 * (lo + hi);
    (angle(mid) < alpha ? lo : hi) = mid;
  }
  return lo;
}

// rising_side, or an Error saying that α is beyond what this box and model allow (§2.4.1).
template <typename Rest>
double bisect_side(double alpha, double b, Rest rest, const std::string& where) {
  const double v = rising_side(alpha, b, rest);
  if (std::isnan(v))
    fail(where, "α = " + degrees(alpha) + " is above the largest angle Eq. 2.2 gives for a box of " +
                    number(b) + " m in this model; choose a smaller α or a larger model");
  return v;
}

using Vec = std::array<double, 3>;

Vec direction(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// The checker's geometry: cell [0, v]³, C at its centre, box C ± b/2, model [0, l]² × [0, h].
struct CheckerScene {
  double v, b, l, h;

  // ∠PV'Q for direction u and corner V'; 0 when the ray leaves the model inside the box.
  double angle(const Vec& u, const Vec& corner) const {
    const double c = v / 2;
    const double t_box = (b / 2) / std::max({std::abs(u[0]), std::abs(u[1]), std::abs(u[2])});
    const Vec hi = {l, l, h};
    double t_model = INFINITY;
    for (int a = 0; a < 3; ++a) {
      if (u[a] > 0) t_model = std::min(t_model, (hi[a] - c) / u[a]);
      if (u[a] < 0) t_model = std::min(t_model, -c / u[a]);
    }
    if (!(t_model > t_box)) return 0.0;
    Vec q, p;
    for (int a = 0; a < 3; ++a) {
      q[a] = c + u[a] * t_box - corner[a];
      p[a] = c + u[a] * t_model - corner[a];
    }
    const Vec cross = {q[1] * p[2] - q[2] * p[1], q[2] * p[0] - q[0] * p[2], q[0] * p[1] - q[1] * p[0]};
    const double dot = q[0] * p[0] + q[1] * p[1] + q[2] * p[2];
    return std::atan2(std::hypot(cross[0], cross[1], cross[2]), dot);
  }
};

// Pattern search on (θ, φ) from a starting direction, the step halving down to 1e-7 rad: the
// angle is smooth within a pair of faces (box face, model face), and the grid start lies in
// the right pair.
double refine(const CheckerScene& scene, const Vec& corner, double& theta, double& phi, double step) {
  double best = scene.angle(direction(theta, phi), corner);
  while (step > 1e-7) {
    bool moved = false;
    for (const auto& [dt, dp] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const double t = theta + dt * step, p = phi + dp * step;
      const double a = scene.angle(direction(t, p), corner);
      if (a > best) best = a, theta = t, phi = p, moved = true;
    }
    if (!moved) step /= 2;
  }
  return best;
}

}  // namespace

double parallax_angle(double s, double t, double t_prime) {
  return std::atan((t + t_prime) / s) - std::atan(t / s);
}

double eq22_angle(double v, double b, double l) { return eq22_with_rest(v, b, l - v); }

double eq22_viewcell_side(double alpha, double b, double l) {
  require_positive(alpha, "α");
  require_positive(b, "the box side b");
  require_positive(l, "the model length l");
  if (!(b < l)) fail("stratify plan", "the box side b must be smaller than the model length l");
  return bisect_side(alpha, b, [l](double v) { return l - v; }, "stratify plan (Eq. 2.2)");
}

double strict_viewcell_side(double alpha, double b) {
  require_positive(alpha, "α");
  require_positive(b, "the box side b");
  const double s = std::sin(std::min(alpha, std::numbers::pi / 2));
  return b * s / (std::sqrt(3.0) + s);
}

WorstCase worst_case_angle(double v, double b, const ModelExtent& model) {
  require_positive(v, "the viewcell side v");
  require_positive(b, "the box side b");
  require_positive(model.length, "the model length");
  require_positive(model.height, "the model height");
  const CheckerScene scene{v, b, model.length, model.height};
  constexpr int kTheta = 180, kPhi = 360;
  const double d_theta = std::numbers::pi / kTheta, d_phi = 2 * std::numbers::pi / kPhi;
  WorstCase worst;
  for (int corner_bits = 0; corner_bits < 8; ++corner_bits) {
    const Vec corner = {corner_bits & 1 ? v : 0.0, corner_bits & 2 ? v : 0.0, corner_bits & 4 ? v : 0.0};
    double best = -1, best_theta = 0, best_phi = 0;
    for (int i = 0; i < kTheta; ++i)
      for (int j = 0; j < kPhi; ++j) {
        const double theta = (i + 0.5) * d_theta, phi = (j + 0.5) * d_phi;
        const double a = scene.angle(direction(theta, phi), corner);
        if (a > best) best = a, best_theta = theta, best_phi = phi;
      }
    best = refine(scene, corner, best_theta, best_phi, d_theta);
    if (best > worst.angle) {
      worst.angle = best;
      const Vec u = direction(best_theta, best_phi);
      std::copy(u.begin(), u.end(), worst.direction);
      std::copy(corner.begin(), corner.end(), worst.corner);
    }
  }
  return worst;
}

double viewcell_side(Sizing sizing, double alpha, double b, const ModelExtent& model) {
  switch (sizing) {
    case Sizing::kEq22: return eq22_viewcell_side(alpha, b, model.length);
    case Sizing::kStrict: return strict_viewcell_side(alpha, b);
    case Sizing::kNumerical: break;
  }
  // The strict side is a true bound and Eq. 2.2's is exceeded, so the answer lies between them.
  double lo = strict_viewcell_side(alpha, b), hi = eq22_viewcell_side(alpha, b, model.length);
  if (worst_case_angle(hi, b, model).angle <= alpha) return hi;
  for (int i = 0; i < 40 && hi - lo > 1e-6 * b; ++i) {
    const double mid = 0.5 * (lo + hi);
    (worst_case_angle(mid, b, model).angle <= alpha ? lo : hi) = mid;
  }
  return lo;
}

BoxSizing box_side_from_budget(const HardwareBudget& h) {
  require_positive(h.triangles_per_second, "the triangles per second");
  require_positive(h.textured_fill_per_second, "the textured fill rate");
  require_positive(h.frame_rate, "the frame rate");
  require_positive(h.viewport_pixels, "the viewport's pixels");
  require_positive(h.textured_fraction, "the textured fraction of the screen");
  require_positive(h.density, "the polygon density");
  require_positive(h.frustum_fraction, "the frustum's fraction of the box");
  BoxSizing s;
  s.polygons_per_frame = h.triangles_per_second / h.frame_rate;
  s.fill_per_frame = h.textured_fill_per_second / h.frame_rate;
  s.textured_pixels = h.viewport_pixels * h.textured_fraction;
  if (!(s.textured_pixels < s.fill_per_frame))
    fail("stratify plan (Eq. 2.3)", "fill is the bottleneck: " + number(s.textured_pixels) +
                                        " textured pixels a frame against " + number(s.fill_per_frame) +
                                        " the fill rate allows; lower the frame rate or the viewport");
  s.b = std::cbrt(s.polygons_per_frame / (h.density * h.frustum_fraction));
  return s;
}

CellCount count_viewcells(double v, double x, double y, double h) {
  require_positive(v, "the viewcell side v");
  require_positive(x, "the model's x extent");
  require_positive(y, "the model's y extent");
  require_positive(h, "the model height");
  // 1e-9 of slack: a side that divides the extent exactly must not count one more row.
  auto rows = [v](double extent) { return static_cast<uint64_t>(std::ceil(extent / v - 1e-9)); };
  return {rows(x) * rows(y) * rows(h), x * y * h / (v * v * v)};
}

namespace {

// The plan for one f, or nullopt when some level's Eq. 4.1 has no solution (a box too small for
// the distance to the next shell). REQUIRES: the arguments checked by multi_shell.
std::optional<ShellPlan> try_multi_shell(double alpha, double b0, double f, ShellSpacing spacing,
                                         const ModelExtent& model) {
  std::vector<double> boxes;
  for (double bi = b0; bi < model.length && boxes.size() < 64;
       bi = spacing == ShellSpacing::kLinear ? bi * f : std::pow(bi, f))
    boxes.push_back(bi);
  ShellPlan plan;
  plan.shells.resize(boxes.size());
  for (size_t k = boxes.size(); k-- > 0;) {
    Shell& s = plan.shells[k];
    s.b = boxes[k];
    const bool outermost = k + 1 == boxes.size();
    const double rest = outermost ? 0.0 : plan.shells[k + 1].v / 2 + plan.shells[k + 1].b / 2;
    s.v = outermost ? rising_side(alpha, s.b, [&](double v) { return model.length - v; })
                    : rising_side(alpha, s.b, [rest](double) { return rest; });
    if (std::isnan(s.v)) return std::nullopt;
    s.l = outermost ? model.length : s.v + rest;
    s.cells = count_viewcells(s.v, model.length, model.length, model.height).grid;
    plan.cells += s.cells;
  }
  return plan;
}

void check_shell_arguments(double alpha, double b0, ShellSpacing spacing, const ModelExtent& model) {
  require_positive(alpha, "α");
  require_positive(b0, "the innermost box side b_0");
  require_positive(model.length, "the model length");
  require_positive(model.height, "the model height");
  if (!(b0 < model.length)) fail("stratify plan", "the innermost box b_0 must be smaller than the model length");
  if (spacing == ShellSpacing::kExponential && !(b0 > 1.0))
    fail("stratify plan", "exponential shell spacing needs b_0 > 1 m (b_i = b_0^(f^i))");
}

}  // namespace

ShellPlan multi_shell(double alpha, double b0, double f, ShellSpacing spacing, const ModelExtent& model) {
  check_shell_arguments(alpha, b0, spacing, model);
  if (!(f > 1.0) || !std::isfinite(f)) fail("stratify plan", "the shell factor f must be greater than 1");
  std::optional<ShellPlan> plan = try_multi_shell(alpha, b0, f, spacing, model);
  if (!plan)
    fail("stratify plan (Eq. 4.1)", "with f = " + number(f) +
                                        " some shell's box is too small for α at the distance of the next; "
                                        "choose a smaller f or a larger α");
  return *plan;
}

ShellSearch best_shell_spacing(double alpha, double b0, ShellSpacing spacing, const ModelExtent& model,
                               double f_min, double f_max, double step) {
  check_shell_arguments(alpha, b0, spacing, model);
  if (!(f_min > 1.0 && f_max >= f_min && step > 0) || !std::isfinite(f_max))
    fail("stratify plan", "the shell factor search needs 1 < f_min <= f_max and a positive step");
  ShellSearch best;
  for (double f = f_min; f <= f_max + 1e-12; f += step) {
    std::optional<ShellPlan> plan = try_multi_shell(alpha, b0, f, spacing, model);
    if (plan && (best.plan.shells.empty() || plan->cells < best.plan.cells)) best = {f, std::move(*plan)};
  }
  if (best.plan.shells.empty()) fail("stratify plan (Eq. 4.1)", "no shell factor in the range has a solution for every shell");
  return best;
}

ShellCosts shell_costs(const ShellPlan& plan, double model_volume, double textures_per_cell,
                       double pixels_per_texture, double bytes_per_pixel, double speed) {
  ShellCosts c;
  for (const Shell& s : plan.shells) {
    const double per_cell = textures_per_cell * pixels_per_texture * bytes_per_pixel;
    c.texture_bytes += model_volume * per_cell / (s.v * s.v * s.v);
    c.update_bytes_per_s += speed * per_cell / s.v;
    c.update_as_printed += speed * per_cell / (s.v * s.v * s.v);
  }
  return c;
}

double crossings_per_second(double speed, double v) { return speed / v; }

double preprocessing_seconds(double polygons, double cells, double polygons_per_second) {
  return polygons * cells / polygons_per_second;
}

int face_resolution_for_screen(int height_px, double fov_y) {
  if (height_px < 1 || !(fov_y > 0.0 && fov_y < std::numbers::pi))
    fail("stratify", "a screen needs a height of 1 pixel or more and a vertical field of view between 0° and 180°");
  const double r = std::ceil(double(height_px) / std::tan(0.5 * fov_y) - 1e-9);
  if (!(r <= double(1 << 20)))
    fail("stratify", "a screen " + std::to_string(height_px) + " pixels high with so narrow a field of view needs faces over 2^20 texels a side");
  return std::max(1, int(r));
}

}  // namespace cellwalk::stratified
