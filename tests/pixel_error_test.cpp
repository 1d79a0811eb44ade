// Tests of the pixel error (src/metrics/pixel_error.cpp) and its distance transform
// (src/metrics/distance_transform.cpp): the transform and the per-pixel distances against
// brute-force nearest-pixel oracles on random images; known cases (an image against itself, an
// object moved by a vector, a silhouette one pixel wider, a missing and an extra object); and
// how compare_images and summarize carry the figures.
#include "cellwalk/metrics/pixel_error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/metrics/fidelity.hpp"
#include "metrics/distance_transform.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Inclusive rectangle of pixels.
struct Rect {
  int x0, y0, x1, y1;
  int area() const { return (x1 - x0 + 1) * (y1 - y0 + 1); }
};

IdImage blank(int width, int height) {
  return {width, height, std::vector<uint32_t>(size_t(width) * size_t(height), kBackgroundId)};
}

// Colour does not enter the pixel error; compare_images needs some.
Image blank_color(int width, int height) {
  return {width, height, std::vector<uint8_t>(size_t(width) * size_t(height) * 4, 0)};
}

void paint(IdImage& image, const Rect& r, uint32_t id) {
  for (int y = std::max(r.y0, 0); y <= std::min(r.y1, image.height - 1); ++y)
    for (int x = std::max(r.x0, 0); x <= std::min(r.x1, image.width - 1); ++x)
      image.ids[size_t(y) * size_t(image.width) + size_t(x)] = id;
}

Rect moved(const Rect& r, int dx, int dy) {
  return {r.x0 + dx, r.y0 + dy, r.x1 + dx, r.y1 + dy};
}

// The oracle of the definition: every pixel of `reference` tried.
std::vector<double> brute_force_distances(const IdImage& shown, const IdImage& reference) {
  std::vector<double> d(shown.ids.size(), 0.0);
  for (int py = 0; py < shown.height; ++py)
    for (int px = 0; px < shown.width; ++px) {
      const size_t p = size_t(py) * size_t(shown.width) + size_t(px);
      if (shown.ids[p] == reference.ids[p]) continue;
      int64_t best = -1;
      for (int qy = 0; qy < shown.height; ++qy)
        for (int qx = 0; qx < shown.width; ++qx) {
          if (reference.ids[size_t(qy) * size_t(shown.width) + size_t(qx)] != shown.ids[p])
            continue;
          const int64_t d2 = int64_t(qx - px) * (qx - px) + int64_t(qy - py) * (qy - py);
          if (best < 0 || d2 < best) best = d2;
        }
      d[p] = best < 0 ? kInf : std::sqrt(double(best));
    }
  return d;
}

TEST(DistanceTransform, MatchesBruteForceOnRandomImages) {
  Random random(14);
  const int sizes[][2] = {{1, 1}, {1, 17}, {23, 1}, {2, 2}, {31, 19}, {40, 40}, {64, 7}};
  for (const auto& [w, h] : sizes)
    for (double density : {0.0, 0.002, 0.03, 0.3, 1.0}) {
      std::vector<uint8_t> sites(size_t(w) * size_t(h));
      for (uint8_t& s : sites) s = random.chance(density) ? 1 : 0;
      const std::vector<uint32_t> got = squared_distance_transform(sites, w, h);
      ASSERT_EQ(got.size(), sites.size());
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          uint64_t best = kNoSite;
          for (int sy = 0; sy < h; ++sy)
            for (int sx = 0; sx < w; ++sx)
              if (sites[size_t(sy) * size_t(w) + size_t(sx)])
                best =
                    std::min<uint64_t>(best, uint64_t((x - sx) * (x - sx) + (y - sy) * (y - sy)));
          ASSERT_EQ(got[size_t(y) * size_t(w) + size_t(x)], best)
              << w << "×" << h << " density " << density << " at " << x << "," << y;
        }
    }
}

TEST(DistanceTransform, RefusesAMaskOfTheWrongSize) {
  EXPECT_THROW(squared_distance_transform(std::vector<uint8_t>(5), 2, 3), Error);
  EXPECT_THROW(squared_distance_transform({}, -1, 0), Error);
  EXPECT_TRUE(squared_distance_transform({}, 0, 0).empty());
}

// A random frame: rectangles of random ids painted over each other on background.
IdImage random_frame(Random& random, int width, int height, int objects, uint32_t first_id) {
  IdImage image = blank(width, height);
  for (int i = 0; i < objects; ++i) {
    const int x = int(random.integer(-3, width - 1)), y = int(random.integer(-3, height - 1));
    const Rect r{x, y, x + int(random.integer(0, width / 3)),
                 y + int(random.integer(0, height / 3))};
    paint(image, r, first_id + uint32_t(random.integer(0, objects)));
  }
  return image;
}

// The truth perturbed as renderings differ: objects moved a little, repainted far away,
// dropped, or new; and a sprinkle of single wrong pixels.
IdImage perturbed(Random& random, const IdImage& truth, int objects) {
  IdImage test = truth;
  for (int i = 0; i < 2 * objects + 4; ++i) {
    const int x = int(random.integer(0, truth.width - 1)),
              y = int(random.integer(0, truth.height - 1));
    const Rect r{x, y, x + int(random.integer(0, 8)), y + int(random.integer(0, 8))};
    const uint32_t id =
        random.chance(0.2) ? kBackgroundId : uint32_t(random.integer(1, objects + 3));
    paint(test, random.chance(0.5) ? r : moved(r, int(random.integer(-2, 2)), 1), id);
  }
  for (uint32_t& id : test.ids)
    if (random.chance(0.03)) id = uint32_t(random.integer(0, objects + 3));
  return test;
}

// The 99.9th percentile by nearest rank, from a sorted copy, in integers: rank ceil(999 n / 1000).
double oracle_p999(std::vector<double> finite) {
  if (finite.empty()) return 0.0;
  std::sort(finite.begin(), finite.end());
  return finite[(999 * finite.size() + 999) / 1000 - 1];
}

TEST(PixelError, DistancesAndStatsMatchBruteForce) {
  Random random(2026);
  for (int trial = 0; trial < 16; ++trial) {
    const int w = int(random.integer(8, 100)), h = int(random.integer(8, 80));
    const int objects = int(random.integer(1, 12));
    const IdImage truth = random_frame(random, w, h, objects, 1);
    const IdImage test = perturbed(random, truth, objects);
    for (const auto& [shown, reference] : {std::pair(&test, &truth), std::pair(&truth, &test)}) {
      const std::vector<double> expected = brute_force_distances(*shown, *reference);
      const std::vector<double> got = pixel_distances(*shown, *reference);
      ASSERT_EQ(got.size(), expected.size());
      for (size_t p = 0; p < got.size(); ++p)
        ASSERT_EQ(got[p], expected[p]) << "trial " << trial << " pixel " << p;
      std::vector<double> finite;
      uint64_t unmatched = 0;
      for (double d : expected) {
        if (std::isinf(d))
          ++unmatched;
        else if (d > 0)
          finite.push_back(d);
      }
      const PixelErrorStats stats = pixel_error(*shown, *reference);
      EXPECT_EQ(stats.unmatched, unmatched);
      EXPECT_EQ(stats.max_px,
                finite.empty() ? 0.0 : *std::max_element(finite.begin(), finite.end()));
      EXPECT_EQ(stats.p999_px, oracle_p999(finite));
      // The worst pixel is the first at the maximum, or none when nothing differs.
      const auto worst = std::find_if(expected.begin(), expected.end(), [&](double d) {
        return d > 0 && !std::isinf(d) && d == stats.max_px;
      });
      EXPECT_EQ(stats.worst_pixel, worst == expected.end() ? -1 : worst - expected.begin());
    }
  }
}

// Enough differing pixels (over a thousand) that the 99.9th percentile is not the maximum.
TEST(PixelError, PercentileLeavesOutTheWorstTenthOfAPercent) {
  std::vector<double> distances(3000, 1.0);
  distances[0] = 0.0;                 // agrees: not in the sample
  distances[1] = kInf;                // unmatched: counted apart
  distances[2] = distances[3] = 9.0;  // the worst 2 of 2998
  distances[4] = 2.0;
  const PixelErrorStats s = pixel_error_stats(distances);
  EXPECT_EQ(s.unmatched, 1u);
  EXPECT_EQ(s.max_px, 9.0);
  // Rank ceil(0.999 · 2998) = 2996 of the sorted sample [1 × 2995, 2, 9, 9] is the 2; with a
  // third 9 it would be a 9.
  EXPECT_EQ(s.p999_px, 2.0);
}

TEST(PixelError, IsZeroAgainstItself) {
  Random random(7);
  const IdImage frame = random_frame(random, 64, 48, 20, 1);
  const PixelErrorStats s = pixel_error(frame, frame);
  EXPECT_EQ(s.max_px, 0.0);
  EXPECT_EQ(s.p999_px, 0.0);
  EXPECT_EQ(s.unmatched, 0u);
  const std::vector<double> d = pixel_distances(frame, frame);
  EXPECT_TRUE(std::all_of(d.begin(), d.end(), [](double v) { return v == 0.0; }));
}

// A rectangle moved by (dx, dy) over background: in both directions the farthest differing
// pixel is the moved corner, |(dx, dy)| from the old one. A still object beside it stays out.
TEST(PixelError, ARectangleMovedBySGivesLengthOfS) {
  const int moves[][2] = {{1, 0}, {3, 0}, {0, -5}, {-7, 0}, {2, 2}, {-3, 4}, {12, 0}, {0, 20}};
  for (const auto& [dx, dy] : moves) {
    IdImage truth = blank(120, 90), test = blank(120, 90);
    const Rect object{40, 30, 65, 50}, still{2, 2, 10, 80};
    paint(truth, object, 5);
    paint(test, moved(object, dx, dy), 5);
    paint(truth, still, 9);
    paint(test, still, 9);
    const double length = std::hypot(double(dx), double(dy));
    for (const PixelErrorStats& s : {pixel_error(test, truth), pixel_error(truth, test)}) {
      EXPECT_DOUBLE_EQ(s.max_px, length) << dx << "," << dy;
      EXPECT_LE(s.p999_px, length);
      EXPECT_GE(s.p999_px, 1.0);
      EXPECT_EQ(s.unmatched, 0u);
    }
  }
}

// Each rectangle grown by a pixel towards its four neighbours (not the diagonals, which are √2
// away): every differing pixel is 1 from its match both ways. The rectangles keep 3 pixels
// apart and 2 from the border, so the grown ones leave background between them.
TEST(PixelError, ASilhouetteOnePixelWiderGivesAtMostOne) {
  Random random(11);
  for (int trial = 0; trial < 20; ++trial) {
    IdImage truth = blank(100, 80), test = blank(100, 80);
    for (uint32_t id = 1; id <= 8; ++id) {
      const int x = 2 + 12 * int(id - 1), y = int(random.integer(2, 40));
      const Rect r{x, y, x + int(random.integer(0, 8)), y + int(random.integer(0, 36))};
      paint(test, {r.x0 - 1, r.y0, r.x1 + 1, r.y1}, id);
      paint(test, {r.x0, r.y0 - 1, r.x1, r.y1 + 1}, id);
      paint(truth, r, id);
    }
    for (const PixelErrorStats& s : {pixel_error(test, truth), pixel_error(truth, test)}) {
      EXPECT_EQ(s.max_px, 1.0);
      EXPECT_EQ(s.p999_px, 1.0);
      EXPECT_EQ(s.unmatched, 0u);
    }
  }
}

// An object one image draws and the other does not: from the image that has it, none of its
// pixels has a match, and they add nothing finite; from the other image they measure the hole,
// how far each pixel is from the background around it (at most half the rectangle's smaller
// side, rounded up). Missing from the test, then extra in it.
TEST(PixelError, AMissingObjectIsUnmatchedNotFinite) {
  IdImage with = blank(80, 60), without = blank(80, 60);
  const Rect kept{5, 5, 20, 20}, lone{40, 10, 50, 45};  // 11 × 36
  paint(with, kept, 1);
  paint(without, kept, 1);
  paint(with, lone, 2);
  for (bool missing : {true, false}) {
    const IdImage& truth = missing ? with : without;
    const IdImage& test = missing ? without : with;
    const PixelErrorStats from_lone = missing ? pixel_error(truth, test) : pixel_error(test, truth);
    const PixelErrorStats into_hole = missing ? pixel_error(test, truth) : pixel_error(truth, test);
    EXPECT_EQ(from_lone.unmatched, uint64_t(lone.area()));
    EXPECT_EQ(from_lone.max_px, 0.0);
    EXPECT_EQ(from_lone.p999_px, 0.0);
    EXPECT_EQ(into_hole.unmatched, 0u);
    EXPECT_EQ(into_hole.max_px, 6.0);  // the middle column, x = 45, is 6 from x = 39 and x = 51
    const FidelityFrame f =
        compare_images(blank_color(80, 60), truth, blank_color(80, 60), test, nullptr);
    EXPECT_EQ(f.missed_objects, missing ? 1u : 0u);
    EXPECT_EQ(f.missed_ids, missing ? std::vector<uint32_t>{2} : std::vector<uint32_t>{});
    EXPECT_EQ(f.largest_missed_pixels, missing ? uint64_t(lone.area()) : 0u);
    EXPECT_EQ((missing ? f.truth_to_test : f.test_to_truth).unmatched, uint64_t(lone.area()));
  }
}

TEST(PixelError, RefusesImagesOfDifferentSizes) {
  EXPECT_THROW(pixel_distances(blank(4, 3), blank(3, 4)), Error);
  IdImage short_ids = blank(4, 3);
  short_ids.ids.pop_back();
  EXPECT_THROW(pixel_distances(short_ids, short_ids), Error);
}

// compare_images carries both directions, test -> truth and truth -> test.
TEST(PixelError, CompareImagesReportsBothDirections) {
  Random random(3);
  const IdImage truth_ids = random_frame(random, 40, 30, 8, 1);
  const IdImage test_ids = perturbed(random, truth_ids, 8);
  const FidelityFrame f =
      compare_images(blank_color(40, 30), truth_ids, blank_color(40, 30), test_ids, nullptr);
  const PixelErrorStats to_truth = pixel_error(test_ids, truth_ids);
  const PixelErrorStats to_test = pixel_error(truth_ids, test_ids);
  EXPECT_EQ(f.test_to_truth.max_px, to_truth.max_px);
  EXPECT_EQ(f.test_to_truth.p999_px, to_truth.p999_px);
  EXPECT_EQ(f.test_to_truth.unmatched, to_truth.unmatched);
  EXPECT_EQ(f.truth_to_test.max_px, to_test.max_px);
  EXPECT_EQ(f.truth_to_test.p999_px, to_test.p999_px);
  EXPECT_EQ(f.truth_to_test.unmatched, to_test.unmatched);
  EXPECT_EQ(f.pixel_error_max_px(), std::max(to_truth.max_px, to_test.max_px));
  EXPECT_EQ(f.pixel_error_p999_px(), std::max(to_truth.p999_px, to_test.p999_px));
}

// The summary: the worse direction of each frame, its largest over frames, and the share of
// frames above 1 px (1 px itself is not above).
TEST(PixelError, SummaryTakesTheWorseDirectionAndCountsFramesOver1Px) {
  std::vector<FidelityFrame> frames(4);
  frames[0].test_to_truth = {3.0, 1.0, 5};
  frames[0].truth_to_test = {1.0, 1.0, 2};
  frames[1].truth_to_test = {1.0, 1.0, 0};
  frames[2].truth_to_test = {7.5, 2.5, 1};
  frames[0].largest_missed_pixels = 3;
  frames[2].largest_missed_pixels = 11;
  // frames[3] identical: all zero.
  const FidelitySummary s = summarize(frames);
  EXPECT_EQ(s.largest_missed_pixels, 11u);
  EXPECT_EQ(s.max_pixel_error_px, 7.5);
  EXPECT_EQ(s.max_pixel_error_p999_px, 2.5);
  EXPECT_DOUBLE_EQ(s.pixel_error_over_1px_fraction, 2.0 / 4.0);       // frames 0 and 2
  EXPECT_DOUBLE_EQ(s.pixel_error_p999_over_1px_fraction, 1.0 / 4.0);  // frame 2
  EXPECT_EQ(s.unmatched_test_pixels, 5u);
  EXPECT_EQ(s.unmatched_truth_pixels, 3u);
  const nlohmann::json j = nlohmann::json::parse(to_json(s));
  EXPECT_EQ(j["pixel_error"]["max_px"], 7.5);
  EXPECT_EQ(j["pixel_error"]["p999_px"], 2.5);
  EXPECT_EQ(j["pixel_error"]["frames_max_over_1px"], 0.5);
  EXPECT_EQ(j["pixel_error"]["unmatched_truth_pixels"], 3);
}

// Every row of the fidelity CSV has one value under each heading, and each value is its own
// column's (the header once lacked missed_drawn and largest_missed_pixels).
TEST(PixelError, FidelityCsvRowsMatchTheirHeader) {
  FidelityFrame f;
  f.frame = 30;
  f.visible_objects = 9;
  f.missed_objects = 2;
  f.missed_drawn = 1;
  f.largest_missed_pixels = 17;
  f.missed_ids = {4, 8};
  f.width = 10;
  f.test_to_truth = {2.5, 2.0, 3, 12};
  const test::TempDir dir;
  write_fidelity_csv({f}, dir.file("f.csv"));
  std::ifstream in(dir.file("f.csv"));
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  const auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    return cells;
  };
  const std::vector<std::string> names = split(header), values = split(row);
  ASSERT_EQ(names.size(), values.size()) << header << "\n" << row;
  const auto value = [&](const std::string& name) {
    const auto at = std::find(names.begin(), names.end(), name);
    return at == names.end() ? std::string("(no column)") : values[size_t(at - names.begin())];
  };
  EXPECT_EQ(value("missed_objects"), "2");
  EXPECT_EQ(value("missed_drawn"), "1");
  EXPECT_EQ(value("largest_missed_pixels"), "17");
  EXPECT_EQ(value("test_to_truth_max_px"), "2.5");
  EXPECT_EQ(value("worst_x"), "2");
  EXPECT_EQ(value("worst_y"), "1");
  EXPECT_EQ(value("missed_object_ids"), "3 7");  // object ids: pixel ids less one
}

}  // namespace
}  // namespace cellwalk
