#include "experiments/common/svg_plot.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "cellwalk/core/error.hpp"

namespace cellwalk {
namespace {

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(SvgPlot, DrawsOneLineAndOneLegendEntryPerSeries) {
  LinePlot plot;
  plot.title = "hits <&> misses";
  plot.series = {{"LRU", {{0.1, 0.2}, {0.5, 0.6}, {1.0, 0.9}}}, {"DoV", {{0.1, 0.3}, {1.0, 0.9}}}};
  const std::string svg = render_svg(plot);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(count(svg, "<polyline"), 2u);
  EXPECT_EQ(count(svg, "<circle"), 5u);
  EXPECT_NE(svg.find(">LRU<"), std::string::npos);
  EXPECT_NE(svg.find("hits &lt;&amp;&gt; misses"), std::string::npos);  // escaped, still valid XML
}

TEST(SvgPlot, LogAxisRefusesNonPositiveX) {
  LinePlot plot;
  plot.log_x = true;
  plot.series = {{"a", {{0.0, 1.0}, {1.0, 2.0}}}};
  EXPECT_THROW(render_svg(plot), Error);
}

TEST(SvgPlot, EmptyAndDegenerateDataStillRender) {
  LinePlot plot;
  EXPECT_NE(render_svg(plot).find("</svg>"), std::string::npos);
  plot.series = {{"one point", {{2.0, 3.0}}}};
  plot.log_x = true;
  EXPECT_EQ(render_svg(plot).find("nan"), std::string::npos);
}

void expect_ticks(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i)
    EXPECT_NEAR(got[i], want[i], 1e-12 * std::abs(want[i])) << i;
}

TEST(SvgPlot, TicksAreOneTwoFiveSteps) {
  expect_ticks(axis_ticks(0.0, 1.0, false), {0.0, 0.2, 0.4, 0.6, 0.8, 1.0});
  expect_ticks(axis_ticks(-3.0, 27.0, false), {0.0, 5.0, 10.0, 15.0, 20.0, 25.0});
  expect_ticks(axis_ticks(0.02, 1.0, true), {0.02, 0.05, 0.1, 0.2, 0.5, 1.0});
  EXPECT_TRUE(axis_ticks(1.0, 1.0, false).empty());
}

}  // namespace
}  // namespace cellwalk
