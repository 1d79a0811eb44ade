// Stratified rendering (seed 002, Xiong 1996; digest 002 §3.2–§3.4, §3.9–§3.11): how large the
// viewcells and their bounding boxes may be. A viewcell is a cube of side v; its bounding box a
// concentric cube of side b > v; everything outside the box is drawn from the cell centre C onto
// the box faces. Given b, motion parallax bounds v so that a far point seen from anywhere in the
// cell is displaced from its texture proxy by at most α (§2.3). b itself comes from the
// hardware's polygon budget and the polygon density (§2.4.2).
//
// All angles are in radians, all lengths in metres. Every function is pure and thread-safe.
#pragma once

#include <cstdint>
#include <vector>

namespace cellwalk::stratified {

// Eq. 2.1: the angle ∠PV'Q at a viewpoint V' displaced by s perpendicular to the line V-Q-P,
// where t = |QV| and t' = |PQ|: atan((t + t')/s) − atan(t/s).
// REQUIRES: s > 0, t >= 0, t' >= 0.
double parallax_angle(double s, double t, double t_prime);

// Eq. 2.2: the angle of the worst case "by inspection" (Fig. 2-4) for a cell of side v at a
// corner of a model of length l, with s = v/√2, t = (b − v)/2, t' = l − v − t.
// REQUIRES: 0 < v < b, v < l.
double eq22_angle(double v, double b, double l);

// The v with eq22_angle(v, b, l) = alpha on the rising branch of the angle: it is 0 at v → 0
// and rises, but where l is little more than b it peaks inside (0, b) and falls again (the
// digest's "monotonic" holds only for l well above b), so the smallest solution is the one
// returned. Throws Error when alpha is above the peak (α has an upper bound, §2.4.1) or an
// argument is not finite and positive, or b >= l.
double eq22_viewcell_side(double alpha, double b, double l);

// The strictly safe closed form [ours, digest §3.3]: for P beyond Q on a ray from C,
// α < ∠(Q − V', u) and sin∠ <= (√3 v/2)/((b − v)/2), so v <= b·sin α / (√3 + sin α).
double strict_viewcell_side(double alpha, double b);

// The model the numerical checker sizes against: l × l in the ground plane, `height` tall, the
// cell in a bottom corner (the thesis's worst place, Fig. 2-4). height = l is the cubic model.
struct ModelExtent {
  double length = 1000.0;
  double height = 1000.0;
};

// The true worst angle ∠PV'Q [ours, digest §3.3]: the largest, over ray directions u from C
// and the cell's 8 corners V', of the angle between P − V' and Q − V', where Q is where the ray
// leaves the box and P where it leaves the model (rays that leave the model inside the box see
// nothing far). A grid of directions, then a local refinement around the best of each corner.
struct WorstCase {
  double angle = 0.0;
  double direction[3] = {0, 0, 0};  // u, unit, z up (the model's height axis)
  double corner[3] = {0, 0, 0};     // V', relative to the cell's minimum corner
};
WorstCase worst_case_angle(double v, double b, const ModelExtent& model);

// How v is chosen from (α, b, l).
enum class Sizing {
  kEq22,       // the thesis: Eq. 2.2 (exceeded by 4–10 % on oblique rays)
  kStrict,     // the closed form above: a true bound, 20–30 % smaller cells
  kNumerical,  // the largest v whose worst_case_angle is <= α, by bisection on the checker
};
double viewcell_side(Sizing sizing, double alpha, double b, const ModelExtent& model);

// §2.4.2, Eq. 2.3: the bounding box from the hardware's budget. With P polygons and T textured
// pixels a frame, t screen pixels textured and p near polygons a frame, max(t/T, p/P) = 1, so
// p = P while fill is not the bottleneck (t < T); the frustum holds about `frustum_fraction` of
// the near polygons, so p = b³ ρ · fraction.
struct HardwareBudget {
  double triangles_per_second = 1.8e6;     // Table 2.1, RealityEngine 2
  double textured_fill_per_second = 55e6;  // Table 2.1, the low end
  double frame_rate = 60.0;
  double viewport_pixels = 512.0 * 512.0;
  double textured_fraction = 0.75;
  double density = 1.0;                    // polygons per m³
  double frustum_fraction = 1.0 / 6.0;     // a 90°×90° frustum
};
struct BoxSizing {
  double polygons_per_frame = 0;   // P
  double fill_per_frame = 0;       // T
  double textured_pixels = 0;      // t
  double b = 0;
};
// Throws Error when fill is the bottleneck (t >= T: no polygon budget reaches the frame rate)
// or an argument is not finite and positive.
BoxSizing box_side_from_budget(const HardwareBudget& budget);

// §2.4.3: cells over a box-shaped region, as the thesis counts them (⌈x/v⌉·⌈y/v⌉·⌈h/v⌉) and as
// the plain volume ratio x·y·h / v³.
struct CellCount {
  uint64_t grid = 0;
  double volume_ratio = 0;
};
CellCount count_viewcells(double v, double x, double y, double h);

// §4, the multi-shell extension: nested boxes b_0 < b_1 < ..., level i's textures holding the
// objects between box i and box i+1. b_i = b_0·f^i (linear) or b_0^(f^i) (exponential), for every
// b_i < l; v_i solves Eq. 4.1 from the outermost level inwards with l_i = v_i + v_{i+1}/2 +
// b_{i+1}/2 (l for the outermost), and level i has ⌈l/v_i⌉²·⌈h/v_i⌉ cells (digest §3.11).
enum class ShellSpacing { kLinear, kExponential };
struct Shell {
  double v = 0;
  double b = 0;
  double l = 0;          // l_i of Eq. 4.1
  uint64_t cells = 0;
};
struct ShellPlan {
  std::vector<Shell> shells;  // innermost first
  uint64_t cells = 0;         // Eq. 4.2, counted per level as above
};
// Throws Error for f <= 1, b_0 >= l or a level whose Eq. 4.1 has no solution (a box too small
// for α at the distance of the next shell).
ShellPlan multi_shell(double alpha, double b0, double f, ShellSpacing spacing, const ModelExtent& model);

// The f in [f_min, f_max] (steps of `step`) whose plan has the fewest cells; ties to the smaller f.
// Factors for which some level has no solution are passed over; none at all is an Error.
struct ShellSearch {
  double f = 0;
  ShellPlan plan;
};
ShellSearch best_shell_spacing(double alpha, double b0, ShellSpacing spacing, const ModelExtent& model,
                               double f_min, double f_max, double step);

// Eqs. 4.3–4.5 for a plan: texture bytes over the model (V·M_text·Σ n_i p_i / v_i³) and the
// texture bytes loaded a second at speed s. The thesis prints Σ p_i n_i / v_i³ for the update
// cost (Eq. 4.5), which is dimensionally wrong: the crossing rate of level i is s / v_i
// (digest §3.11). Both are returned; the corrected one is what a walkthrough pays.
struct ShellCosts {
  double texture_bytes = 0;          // Eq. 4.3–4.4
  double update_bytes_per_s = 0;     // Eq. 4.5 corrected: s·Σ p_i n_i M / v_i
  double update_as_printed = 0;      // s·Σ p_i n_i M / v_i³, the printed form
};
ShellCosts shell_costs(const ShellPlan& plan, double model_volume, double textures_per_cell,
                       double pixels_per_texture, double bytes_per_pixel, double speed);

// The face resolution whose texels are as dense as a screen's pixels at the view centre [ours;
// §5.3 fixes 512²]: a 90° face of R texels spans 2/R in tangent at its centre, a screen of H
// pixels and vertical field θ spans 2·tan(θ/2)/H a pixel at its centre, so R = ⌈H / tan(θ/2)⌉
// (512 for 512 pixels at 90°). Not a bound everywhere: a pixel at the screen's edge looking at a
// face's centre spans less (by 1/(1 + tan²(θ/2)(1 + aspect²)) at a corner), where a texel may
// cover 2–4 pixels. Throws Error for H < 1, θ outside (0, π), or an R above 2^20.
int face_resolution_for_screen(int height_px, double fov_y);

// Eq. 3.2's crossing rate s / v (Table 3.2) and Eq. 3.1's preprocessing time j·n / P_sec.
double crossings_per_second(double speed, double v);
double preprocessing_seconds(double polygons, double cells, double polygons_per_second);

}  // namespace cellwalk::stratified
