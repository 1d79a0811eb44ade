// Li & Chiang's relevance matrix (seed 003, "Parameters for Computing a Relevance Matrix";
// cellwalk/systems/lichiang/relevance.hpp has the formula and its readings).
#include "cellwalk/systems/lichiang/relevance.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cellwalk::lichiang {

namespace {

constexpr double kPi = std::numbers::pi;

// The window's row `ahead` of the viewer: its centre is ⌈ν⌉ ahead.
int window_shift(double nu) { return nu > 0.0 ? int(std::ceil(nu)) : 0; }

}  // namespace

double relevance_peak_angle(double omega) { return kPi - 2.0 * std::atan(omega); }

double relevance_falloff(double phi, double omega, const RelevanceParams& p) {
  const double f_max = relevance_peak_angle(omega);
  const double a_peak = p.a_min + (p.a_max - p.a_min) * f_max / kPi;
  if (phi <= f_max) return p.a_min + (a_peak - p.a_min) / f_max * phi;
  return a_peak + (a_peak - p.a_min) / (f_max - 2.0 * kPi) * (phi - f_max);
}

double relevance(double ahead, double right, double omega, const RelevanceParams& p) {
  const double d2 = ahead * ahead + right * right;
  if (d2 == 0.0) return p.c;
  double phi = std::atan2(right, ahead);  // clockwise from the viewing direction
  if (phi < 0.0) phi += 2.0 * kPi;
  return p.c - relevance_falloff(phi, omega, p) * d2;
}

std::vector<RelevanceEntry> relevance_window(double nu, double omega, double yaw, const RelevanceParams& p) {
  const double fx = -std::sin(yaw), fz = -std::cos(yaw);  // the heading; its right is (−fz, fx)
  const int shift = window_shift(nu);
  const double octant = std::round(yaw / (kPi / 4.0)) * (kPi / 4.0);  // the nearest grid direction
  const int cx = int(std::lround(-std::sin(octant))) * shift, cz = int(std::lround(-std::cos(octant))) * shift;
  std::vector<RelevanceEntry> window;
  for (int i = -p.radius; i <= p.radius; ++i)
    for (int j = -p.radius; j <= p.radius; ++j) {
      const double x = cx + i, z = cz + j;
      window.push_back({cx + i, cz + j, relevance(x * fx + z * fz, -x * fz + z * fx, omega, p)});
    }
  std::stable_sort(window.begin(), window.end(), [](const RelevanceEntry& a, const RelevanceEntry& b) {
    if (a.w != b.w) return a.w > b.w;
    return a.dx * a.dx + a.dz * a.dz < b.dx * b.dx + b.dz * b.dz;
  });
  return window;
}

std::vector<std::vector<int>> relevance_matrix(double nu, double omega, const RelevanceParams& p) {
  const int shift = window_shift(nu);
  std::vector<std::vector<int>> rows;
  for (int row = -p.radius; row <= p.radius; ++row) {
    rows.emplace_back();
    for (int right = -p.radius; right <= p.radius; ++right)
      // The printed values are whole: w rounded down (the tolerance keeps exact integers whole).
      rows.back().push_back(int(std::floor(relevance(shift - row, right, omega, p) + 1e-9)));
  }
  return rows;
}

}  // namespace cellwalk::lichiang
