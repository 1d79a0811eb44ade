// A minimal SVG line plot for the bench reports (DESIGN.md "Measuring": `cellwalk bench …`
// renders its figures into docs/results/). Generic on purpose: one chart, axes with ticks,
// one polyline per series and a legend, so every bench subcommand draws with it.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace cellwalk {

struct PlotSeries {
  std::string name;
  std::vector<std::pair<double, double>> points;  // (x, y), joined in the order given
};

struct LinePlot {
  std::string title, x_label, y_label;
  bool log_x = false;  // REQUIRES when set: every x > 0
  // The y range; when y_min >= y_max it is taken from the data. x always spans the data.
  double y_min = 0.0, y_max = 0.0;
  int width = 720, height = 440;  // pixels
  std::vector<PlotSeries> series;
};

// The plot as a standalone SVG document. Text is XML-escaped. Throws Error if log_x is set and
// some x <= 0. A plot without points gives axes without ticks.
std::string render_svg(const LinePlot& plot);

// Tick positions for [lo, hi]: 1-2-5 steps (about `count` of them) on a linear axis, or
// 1-2-5 × powers of ten on a log axis. Exposed for the tests.
std::vector<double> axis_ticks(double lo, double hi, bool log_scale, int count = 6);

}  // namespace cellwalk
