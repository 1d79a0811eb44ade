// Li & Chiang's relevance matrix (seed 003, "Parameters for Computing a Relevance Matrix",
// "Examples of Computed Relevance Matrices"): how relevant each neighbouring viewpoint
// configuration is to the near future, from its distance to the viewer and its angle from the
// viewing direction, bent by the viewer's linear and angular velocity.
//
//   w(a, d) = −a·d² + c
//   a(φ)    = a_min + (a_peak − a_min)/f_max · φ                 for φ ≤ f_max
//           = a_peak + (a_peak − a_min)/(f_max − 2π) · (φ − f_max)  for φ > f_max
//   f_max   = π − 2·tan⁻¹(ω)
//
// Readings the slides leave open, each fixed so that both printed 5×5 matrices come out cell
// for cell (docs/lichiang.md, "The relevance matrix"):
//   - φ is measured clockwise (towards the viewer's right) from the viewing direction, and ω is
//     positive turning left (counter-clockwise): ω < 0 moves the least relevant direction from
//     straight behind towards the left, so the side the viewer turns to stays relevant longer.
//   - The second branch is written in φ − f_max (as printed, a(f) would jump at f_max).
//   - a_peak = a_min + (a_max − a_min)·f_max/π: the rate at which a grows with φ is the same at
//     every ω (with a_peak fixed at a_max the second printed matrix differs in 21 of 25 cells).
//   - ν shifts the window of neighbours ⌈ν⌉ cells ahead (the second matrix's viewer stands one
//     row behind its centre); it does not change a.
//   - The printed values are w rounded down; d is in cells; a_min = 1, a_max = 20, c = 255.
// Units: ν in cells per frame, ω in radians per frame (the slides give none).
#pragma once

#include <vector>

namespace cellwalk::lichiang {

struct RelevanceParams {
  double a_min = 1.0;
  double a_max = 20.0;   // a(π) when ω = 0
  double c = 255.0;
  int radius = 2;        // the window is (2·radius + 1)² configurations
};

// f_max = π − 2·tan⁻¹(ω), in (0, 2π).
double relevance_peak_angle(double omega);
// a(φ) for φ in [0, 2π), clockwise from the viewing direction.
double relevance_falloff(double phi, double omega, const RelevanceParams& params = {});
// w for a configuration `ahead` cells in front of the viewer's and `right` cells to its right.
double relevance(double ahead, double right, double omega, const RelevanceParams& params = {});

// One configuration of the window: its offset in cells from the viewer's along the grid's x and
// z axes, and its relevance.
struct RelevanceEntry {
  int dx = 0, dz = 0;
  double w = 0.0;
};
// The window a viewer looking along `yaw` (radians, the camera's convention) prefetches from:
// (2·radius + 1)² grid offsets around the cell ⌈ν⌉ steps ahead (the heading rounded to the
// nearest of the eight grid directions), most relevant first (ties: nearer first). Each w is
// that of the offset's components along the heading and to its right.
std::vector<RelevanceEntry> relevance_window(double nu, double omega, double yaw, const RelevanceParams& params = {});

// The window as the slides print it: rows front to back, columns left to right, each w rounded
// down to an integer.
std::vector<std::vector<int>> relevance_matrix(double nu, double omega, const RelevanceParams& params = {});

}  // namespace cellwalk::lichiang
