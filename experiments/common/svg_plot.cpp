#include "experiments/common/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>

#include "cellwalk/core/error.hpp"

namespace cellwalk {
namespace {

// Colours distinguishable in print and for the common colour blindnesses (Okabe & Ito 2008).
constexpr const char* kColors[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                   "#E69F00", "#56B4E9", "#000000", "#F0E442"};
constexpr double kLeft = 70, kRight = 170, kTop = 40, kBottom = 55;  // margins, pixels

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Maps data to pixels, one axis.
struct Scale {
  double lo, hi, px_lo, px_hi;
  bool log;
  double operator()(double v) const {
    const double t = log ? (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo))
                         : (v - lo) / (hi - lo);
    return px_lo + t * (px_hi - px_lo);
  }
};

// The data's range on one axis, widened when degenerate so the scale never divides by zero.
std::pair<double, double> data_range(const LinePlot& plot, bool x_axis) {
  double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
  for (const PlotSeries& s : plot.series) {
    for (const auto& [x, y] : s.points) {
      const double v = x_axis ? x : y;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (lo > hi) return {x_axis && plot.log_x ? 1.0 : 0.0, 1.0};
  if (lo == hi) return x_axis && plot.log_x ? std::pair{lo / 2, hi * 2} : std::pair{lo - 1, hi + 1};
  return {lo, hi};
}

std::string axes(const Scale& x, const Scale& y, const LinePlot& plot) {
  std::string svg;
  const auto line = [&](double x1, double y1, double x2, double y2, const char* style) {
    svg += "<line x1=\"" + number(x1) + "\" y1=\"" + number(y1) + "\" x2=\"" + number(x2) +
           "\" y2=\"" + number(y2) + "\" " + style + "/>\n";
  };
  const auto text = [&](double px, double py, const std::string& s, const char* anchor) {
    svg += "<text x=\"" + number(px) + "\" y=\"" + number(py) + "\" text-anchor=\"" + anchor +
           "\">" + escape(s) + "</text>\n";
  };
  for (double t : axis_ticks(x.lo, x.hi, x.log)) {
    line(x(t), y.px_lo, x(t), y.px_hi, "stroke=\"#ddd\"");
    text(x(t), y.px_lo + 18, number(t), "middle");
  }
  for (double t : axis_ticks(y.lo, y.hi, false)) {
    line(x.px_lo, y(t), x.px_hi, y(t), "stroke=\"#ddd\"");
    text(x.px_lo - 6, y(t) + 4, number(t), "end");
  }
  line(x.px_lo, y.px_lo, x.px_hi, y.px_lo, "stroke=\"#000\"");
  line(x.px_lo, y.px_lo, x.px_lo, y.px_hi, "stroke=\"#000\"");
  text((x.px_lo + x.px_hi) / 2, plot.height - 12, plot.x_label, "middle");
  svg += "<text transform=\"translate(16," + number((y.px_lo + y.px_hi) / 2) +
         ") rotate(-90)\" text-anchor=\"middle\">" + escape(plot.y_label) + "</text>\n";
  text(plot.width / 2.0, 24, plot.title, "middle");
  return svg;
}

std::string series_lines(const Scale& x, const Scale& y, const LinePlot& plot) {
  std::string svg;
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    const std::string color = kColors[i % std::size(kColors)];
    std::string points;
    for (const auto& [px, py] : s.points) points += number(x(px)) + "," + number(y(py)) + " ";
    svg += "<polyline fill=\"none\" stroke=\"" + color + "\" stroke-width=\"2\" points=\"" +
           points + "\"/>\n";
    for (const auto& [px, py] : s.points) {
      svg += "<circle cx=\"" + number(x(px)) + "\" cy=\"" + number(y(py)) + "\" r=\"3\" fill=\"" +
             color + "\"/>\n";
    }
    const double ly = kTop + 10 + 20.0 * double(i), lx = plot.width - kRight + 15;
    svg += "<line x1=\"" + number(lx) + "\" y1=\"" + number(ly) + "\" x2=\"" + number(lx + 24) +
           "\" y2=\"" + number(ly) + "\" stroke=\"" + color + "\" stroke-width=\"2\"/>\n";
    svg += "<text x=\"" + number(lx + 30) + "\" y=\"" + number(ly + 4) + "\">" + escape(s.name) +
           "</text>\n";
  }
  return svg;
}

}  // namespace

std::vector<double> axis_ticks(double lo, double hi, bool log_scale, int count) {
  std::vector<double> ticks;
  if (!(lo < hi)) return ticks;
  // Ticks are computed as integer multiples, not accumulated, so labels print without noise.
  if (log_scale) {
    for (int e = int(std::floor(std::log10(lo))); e <= int(std::ceil(std::log10(hi))); ++e) {
      for (double m : {1.0, 2.0, 5.0}) {
        const double t = e < 0 ? m / std::pow(10.0, -e) : m * std::pow(10.0, e);
        if (t >= lo * (1 - 1e-9) && t <= hi * (1 + 1e-9)) ticks.push_back(t);
      }
    }
    return ticks;
  }
  const double raw = (hi - lo) / std::max(count, 1);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * magnitude;
    if (step >= raw * (1 - 1e-9)) break;
  }
  const double eps = 1e-9 * (hi - lo);
  for (auto k = int64_t(std::ceil((lo - eps) / step)); double(k) * step <= hi + eps; ++k) {
    ticks.push_back(double(k) * step);
  }
  return ticks;
}

std::string render_svg(const LinePlot& plot) {
  if (plot.log_x) {
    for (const PlotSeries& s : plot.series) {
      for (const auto& [x, y] : s.points) {
        if (x <= 0) fail("plot \"" + plot.title + "\"", "log x axis needs x > 0, got " + number(x));
      }
    }
  }
  const auto [x_lo, x_hi] = data_range(plot, true);
  const auto [y_lo, y_hi] =
      plot.y_min < plot.y_max ? std::pair{plot.y_min, plot.y_max} : data_range(plot, false);
  const Scale x{x_lo, x_hi, kLeft, plot.width - kRight, plot.log_x};
  const Scale y{y_lo, y_hi, plot.height - kBottom, kTop, false};
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + number(plot.width) +
         "\" height=\"" + number(plot.height) +
         "\" font-family=\"sans-serif\" font-size=\"12\">\n" +
         "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n" + axes(x, y, plot) +
         series_lines(x, y, plot) + "</svg>\n";
}

}  // namespace cellwalk
