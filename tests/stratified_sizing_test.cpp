// Stratified sizing (seed 002 §2.2–§2.4, §4; digest 002 §3.3–§3.11): the thesis's figures and
// the digest's reproductions are the oracle, and the numerical checker is checked against the
// closed forms it must agree with.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/stratified/sizing.hpp"

namespace cellwalk::stratified {
namespace {

double rad(double degrees) { return degrees * std::numbers::pi / 180.0; }
double deg(double radians) { return radians * 180.0 / std::numbers::pi; }

TEST(StratifiedSizing, Eq21IsTheAngleBetweenTheTwoSightLines) {
  // V' at (s, 0), Q at (0, t), P at (0, t + t'): the angle between the two directions.
  const double s = 3, t = 4, tp = 10;
  const double expected = std::atan2(t + tp, s) - std::atan2(t, s);
  EXPECT_NEAR(parallax_angle(s, t, tp), expected, 1e-12);
  EXPECT_NEAR(parallax_angle(s, t, 0), 0.0, 1e-12);
}

TEST(StratifiedSizing, Eq22ReproducesTheThesisViewcells) {
  // §2.4.1 and Table 6.1 (digest §3.3): 6.35, 6.22, 33 and 5 m, to the digest's 4 figures.
  EXPECT_NEAR(eq22_viewcell_side(rad(10), 56, 1000), 6.354, 0.001);
  EXPECT_NEAR(eq22_viewcell_side(rad(10), 56, 10000), 6.222, 0.001);
  EXPECT_NEAR(eq22_viewcell_side(rad(7.5), 330, 1000), 32.81, 0.01);
  EXPECT_NEAR(eq22_viewcell_side(rad(1), 330, 1000), 4.80, 0.005);
  // The side it returns has the angle it was asked for.
  const double v = eq22_viewcell_side(rad(7.5), 330, 1000);
  EXPECT_NEAR(deg(eq22_angle(v, 330, 1000)), 7.5, 1e-6);
}

TEST(StratifiedSizing, Eq22ReproducesTheFigureCurves) {
  // Figs. 2-5 to 2-9 as the digest computed them from Eq. 2.2.
  struct Row { double alpha, b, l, v; };
  const Row rows[] = {{0.1, 1000, 3000, 1.48}, {1, 1000, 3000, 14.6},  {5, 1000, 3000, 68.6},
                      {20, 1000, 3000, 234.6}, {45, 1000, 3000, 481.4}, {10, 10, 3000, 1.11},
                      {10, 300, 3000, 34.7},   {10, 2000, 3000, 313.2}, {10, 1000, 1100, 190.8},
                      {10, 1000, 1e5, 111.3},  {1, 56, 1000, 0.70},     {20, 56, 10000, 11.49}};
  for (const Row& r : rows)
    EXPECT_NEAR(eq22_viewcell_side(rad(r.alpha), r.b, r.l), r.v, r.v * 0.005 + 0.005)
        << r.alpha << "° b " << r.b << " l " << r.l;
}

TEST(StratifiedSizing, Eq22TakesTheRisingBranchWhenTheAnglePeaks) {
  // l = 1100, b = 1000: the angle peaks inside (0, b) and is only 8.05° at v = b, yet 10° is
  // reached at v = 190.8 (Fig. 2-7); the peak is 24.7° near v = 558, and more is refused.
  EXPECT_LT(eq22_angle(999.9, 1000, 1100), rad(8.1));
  const double v = eq22_viewcell_side(rad(10), 1000, 1100);
  EXPECT_NEAR(v, 190.8, 0.1);
  for (double w = v / 16; w < v; w += v / 16) EXPECT_LT(eq22_angle(w, 1000, 1100), rad(10));
  EXPECT_NEAR(eq22_viewcell_side(rad(24.6), 1000, 1100), 520, 40);
  EXPECT_THROW(eq22_viewcell_side(rad(24.8), 1000, 1100), Error);
}

TEST(StratifiedSizing, AnAngleTheModelCannotReachIsRefused) {
  // α has an upper bound (§2.4.1); for l ≫ b the angle rises all the way to v = b, where it is
  // atan(√2 (l − b)/b).
  const double top = std::atan(std::sqrt(2.0) * (1000 - 56) / 56);
  EXPECT_NO_THROW(eq22_viewcell_side(top * 0.999, 56, 1000));
  EXPECT_THROW(eq22_viewcell_side(top * 1.001, 56, 1000), Error);
  EXPECT_THROW(eq22_viewcell_side(rad(10), 1000, 56), Error);
  EXPECT_THROW(eq22_viewcell_side(NAN, 56, 1000), Error);
  EXPECT_THROW(eq22_viewcell_side(rad(10), -1, 1000), Error);
}

TEST(StratifiedSizing, StrictBoundIsTheDigestsClosedForm) {
  EXPECT_NEAR(strict_viewcell_side(rad(10), 56), 5.10, 0.005);
  EXPECT_NEAR(strict_viewcell_side(rad(7.5), 330), 23.1, 0.05);
  EXPECT_NEAR(strict_viewcell_side(rad(1), 330), 3.29, 0.005);
}

TEST(StratifiedSizing, CheckerFindsTheObliqueWorstCaseAboveEq22) {
  // Digest §3.3: at Eq. 2.2's v the true worst angle exceeds α by 4–10 % (cubic model:
  // 10.53°, 7.91°, 1.10°; flat: 10.40° at 10 m high, 7.86° at 67 m).
  struct Row { double alpha, b, height, worst; };
  const Row rows[] = {{10, 56, 1000, 10.53}, {7.5, 330, 1000, 7.91}, {1, 330, 1000, 1.10},
                      {10, 56, 10, 10.40},   {7.5, 330, 67, 7.86},   {1, 330, 67, 1.09}};
  for (const Row& r : rows) {
    const double v = eq22_viewcell_side(rad(r.alpha), r.b, 1000);
    const WorstCase w = worst_case_angle(v, r.b, {1000, r.height});
    EXPECT_NEAR(deg(w.angle), r.worst, 0.01) << r.alpha << "° height " << r.height;
    // Oblique: not along an axis.
    const double axis = std::max({std::abs(w.direction[0]), std::abs(w.direction[1]), std::abs(w.direction[2])});
    EXPECT_LT(axis, std::cos(rad(5)));
  }
}

TEST(StratifiedSizing, CheckerNeverExceedsAlphaAtTheStrictSide) {
  for (const double alpha : {1.0, 7.5, 10.0, 20.0})
    for (const double b : {56.0, 330.0}) {
      const double v = strict_viewcell_side(rad(alpha), b);
      EXPECT_LE(worst_case_angle(v, b, {1000, 1000}).angle, rad(alpha)) << alpha << "° b " << b;
    }
}

TEST(StratifiedSizing, NumericalSizingIsTheLargestSideTheCheckerAccepts) {
  const ModelExtent model{1000, 67};
  const double v = viewcell_side(Sizing::kNumerical, rad(7.5), 330, model);
  EXPECT_GT(v, strict_viewcell_side(rad(7.5), 330));
  EXPECT_LT(v, eq22_viewcell_side(rad(7.5), 330, 1000));
  EXPECT_LE(worst_case_angle(v, 330, model).angle, rad(7.5));
  EXPECT_GT(worst_case_angle(v * 1.01, 330, model).angle, rad(7.5));
}

TEST(StratifiedSizing, Eq23GivesTheThesisBox) {
  // §2.4.2: 1.8M triangles/s at 60 Hz = 30,000 polygons a frame; 1/m³ and the 1/6 frustum rule
  // give b³ = 180,000 m³, b ≈ 56 m; 197k textured pixels are under the 920k fill allows.
  const BoxSizing s = box_side_from_budget({});
  EXPECT_DOUBLE_EQ(s.polygons_per_frame, 30000);
  EXPECT_NEAR(s.fill_per_frame, 916667, 1);
  EXPECT_NEAR(s.textured_pixels, 196608, 1);
  EXPECT_NEAR(s.b, 56.46, 0.01);
  HardwareBudget fill_bound;
  fill_bound.textured_fill_per_second = 10e6;
  EXPECT_THROW(box_side_from_budget(fill_bound), Error);
}

TEST(StratifiedSizing, FaceResolutionForAScreenIsTheSmallestAsDenseAsItsPixelsAtTheCentre) {
  EXPECT_EQ(face_resolution_for_screen(512, M_PI / 2), 512);  // §5.3's faces for its screen
  for (const int height : {1, 240, 480, 1080, 2160})
    for (const double fov_deg : {20.0, 45.0, 60.0, 90.0, 120.0}) {
      const double fov = fov_deg * M_PI / 180;
      const int r = face_resolution_for_screen(height, fov);
      const double pixel = 2 * std::tan(fov / 2) / height;  // tangent span of a pixel at the centre
      EXPECT_LE(2.0 / r, pixel * (1 + 1e-9)) << height << " px at " << fov_deg << "°";
      if (r > 1) {
        EXPECT_GT(2.0 / (r - 1), pixel) << height << " px at " << fov_deg << "°";
      }
    }
  EXPECT_THROW(face_resolution_for_screen(0, 1.0), Error);
  EXPECT_THROW(face_resolution_for_screen(480, 0.0), Error);
  EXPECT_THROW(face_resolution_for_screen(480, M_PI), Error);
  EXPECT_THROW(face_resolution_for_screen(1080, 1e-7), Error);  // would overflow an int
  EXPECT_EQ(face_resolution_for_screen(1, M_PI - 1e-9), 1);
}

TEST(StratifiedSizing, CellCountsOfTheCampusAndTheCity) {
  // §2.4.3: the campus, 1 km × 1 km × 10 m at v = 6.35 → 158²·2 = 49,928 ≈ 50,000; the city,
  // 10 km × 10 km × 100 m at 6.22 m → 4.1×10^7 by volume.
  EXPECT_EQ(count_viewcells(6.35, 1000, 1000, 10).grid, 49928u);
  EXPECT_NEAR(count_viewcells(6.22, 1e4, 1e4, 100).volume_ratio, 4.16e7, 0.01e7);
  EXPECT_EQ(count_viewcells(10, 1000, 1000, 10).grid, 10000u);  // an exact fit adds no row
}

TEST(StratifiedSizing, MultiShellReproducesTables41And42) {
  const ModelExtent campus{1000, 10};
  // The printed f = 1.72 is rounded: 1.7225 gives the printed boxes and cells (digest §3.11).
  const ShellPlan linear = multi_shell(rad(10), 56, 1.7225, ShellSpacing::kLinear, campus);
  EXPECT_EQ(linear.cells, 15230u);
  const uint64_t linear_cells[] = {10000, 3481, 1156, 400, 144, 49};  // Table 4.1 + the 7² level
  const double linear_v[] = {10.0, 17.2, 29.6, 51.1, 88.0};
  ASSERT_EQ(linear.shells.size(), 6u);
  for (size_t i = 0; i < 6; ++i) EXPECT_EQ(linear.shells[i].cells, linear_cells[i]) << i;
  for (size_t i = 0; i < 5; ++i) EXPECT_NEAR(linear.shells[i].v, linear_v[i], 0.1) << i;
  const double linear_b[] = {56.0, 96.4, 166.2, 286.3, 493.3};
  for (size_t i = 0; i < 5; ++i) EXPECT_NEAR(linear.shells[i].b, linear_b[i], 0.5) << i;
  EXPECT_EQ(multi_shell(rad(10), 56, 1.72, ShellSpacing::kLinear, campus).cells, 15230u);

  const ShellPlan exponential = multi_shell(rad(10), 56, 1.1365, ShellSpacing::kExponential, campus);
  EXPECT_EQ(exponential.cells, 15129u);
  const uint64_t exp_cells[] = {10000, 3600, 1156, 324, 49};  // Table 4.2 + the 7² level
  ASSERT_EQ(exponential.shells.size(), 5u);
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ(exponential.shells[i].cells, exp_cells[i]) << i;
  // Each level's v solves Eq. 4.1 with its own l_i.
  for (const Shell& s : linear.shells) EXPECT_NEAR(deg(eq22_angle(s.v, s.b, s.l)), 10.0, 1e-6);
}

TEST(StratifiedSizing, ShellSearchFindsAtMostTheThesisCount) {
  // Just above f = 1.72 v_0 drops below 10 m and the count jumps (two vertical layers).
  const ModelExtent campus{1000, 10};
  EXPECT_GT(multi_shell(rad(10), 56, 1.73, ShellSpacing::kLinear, campus).cells, 25000u);
  const ShellSearch best = best_shell_spacing(rad(10), 56, ShellSpacing::kLinear, campus, 1.05, 3.0, 0.005);
  EXPECT_LE(best.plan.cells, 15230u);
  EXPECT_LT(best.plan.cells, count_viewcells(eq22_viewcell_side(rad(10), 56, 1000), 1000, 1000, 10).grid / 3);
  EXPECT_THROW(multi_shell(rad(10), 56, 1.0, ShellSpacing::kLinear, campus), Error);
}

TEST(StratifiedSizing, Eq45CorrectedScalesWithCrossingsNotVolume) {
  ShellPlan plan;
  plan.shells = {{10, 56, 0, 0}, {20, 100, 0, 0}};
  const ShellCosts c = shell_costs(plan, 1e7, 4, 512 * 512, 4, 1.0);
  const double per_cell = 4.0 * 512 * 512 * 4;
  EXPECT_NEAR(c.texture_bytes, 1e7 * per_cell * (1 / 1000.0 + 1 / 8000.0), 1);
  EXPECT_NEAR(c.update_bytes_per_s, per_cell * (1 / 10.0 + 1 / 20.0), 1e-6);
  EXPECT_NEAR(c.update_as_printed, per_cell * (1 / 1000.0 + 1 / 8000.0), 1e-6);
  // Table 3.2 and Eq. 3.1's campus: 0.2 and 5.6 crossings a second; ~126 h.
  EXPECT_NEAR(crossings_per_second(1.0, 5), 0.2, 1e-12);
  EXPECT_NEAR(crossings_per_second(100 / 3.6, 5), 5.56, 0.01);
  EXPECT_NEAR(preprocessing_seconds(1e7, 81600, 1.8e6) / 3600, 126, 0.5);
}

}  // namespace
}  // namespace cellwalk::stratified

// ---- cellwalk stratify plan ------------------------------------------------------------------

#include <nlohmann/json.hpp>

#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/stored_stratified.hpp"
#include "test_support.hpp"

namespace cellwalk::stratified {
namespace {

TEST(StratifyPlan, ReportsTheThesisCampusInJson) {
  const test::CommandResult r =
      test::run_cellwalk("stratify plan --alpha 10 --box 56 --model-length 1000 --model-height 10 "
                         "--shell-factor 1.7225 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_NEAR(j["sizings"][0]["v"].get<double>(), 6.354, 0.001);
  EXPECT_EQ(j["sizings"][0]["sizing"], "eq22");
  EXPECT_EQ(j["multi_shell"]["cells"].get<uint64_t>(), 15230u);
  // The checker's worst angle: above α for Eq. 2.2, at most α for the strict and numerical sides.
  EXPECT_GT(j["sizings"][0]["worst_angle_deg"].get<double>(), 10.3);
  EXPECT_LE(j["sizings"][1]["worst_angle_deg"].get<double>(), 10.0);
  EXPECT_LE(j["sizings"][2]["worst_angle_deg"].get<double>(), 10.0 + 1e-9);
}

TEST(StratifyPlan, SizesForAWorldFromItsExtentAndDensity) {
  const test::CommandResult r = test::run_cellwalk(
      "stratify plan " + test::source_path("tests/data/seeds/cube.cww") + " --box 0.5 --shells none --no-check --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_FALSE(j["model"]["world"].is_null());
  EXPECT_GT(j["model"]["x"].get<double>(), 0.5);
  EXPECT_TRUE(j["sizings"][0]["worst_angle_deg"].is_null());
}

TEST(StratifyPlan, BadArgumentsGetOneLineAndAFailure) {
  for (const char* args : {"stratify plan --alpha 95", "stratify plan --alpha nan", "stratify plan --box 2000",
                           "stratify plan --alpha 88 --box 56 --shells none", "stratify plan --fill-per-second 1000",
                           "stratify plan --shell-factor 1", "stratify plan no-such.cww"}) {
    const test::CommandResult r = test::run_cellwalk(args);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
  }
}

}  // namespace
}  // namespace cellwalk::stratified

namespace cellwalk::stratified {
namespace {

TEST(StratifyBuild, ScreenGivesTheResolutionAndLevelsCutTheBakedTriangles) {
  const test::TempDir dir;
  const std::string world = dir.file("city.cww");
  for (const std::string& command : {"generate stratified-city --blocks-x 2 --blocks-z 2 -o " + dir.file("city.cwscene"),
                                     "build " + dir.file("city.cwscene") + " -o " + world})
    ASSERT_EQ(test::run_cellwalk(command).exit_code, 0) << command;
  const auto build = [&](const std::string& options) {
    const test::CommandResult r = test::run_cellwalk("stratify build " + world + " -o " + dir.file("s.cww") +
                                                     " --box 60 --alpha 10 --json " + options);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return nlohmann::json::parse(r.output);
  };
  const auto screen = build("--screen 48:90 --far-level-texels 0");
  EXPECT_EQ(screen["resolution"], 48);
  EXPECT_EQ(build("--screen 40:60 --far-level-texels 0")["resolution"], face_resolution_for_screen(40, M_PI / 3));
  const auto coarse = build("--screen 48:90 --far-level-texels 50");
  EXPECT_EQ(coarse["baked_cells"], screen["baked_cells"]);
  EXPECT_LT(coarse["bake_triangles_per_cell"].get<uint64_t>(), screen["bake_triangles_per_cell"].get<uint64_t>());
  // The world records the level bound it was baked with.
  const World baked(dir.file("s.cww"));
  EXPECT_FLOAT_EQ(StoredStratified(baked).params().far_level_texels, 50.0f);
}

TEST(StratifyBuild, BadInputGetsOneLineAndLeavesTheWorldAlone) {
  const test::TempDir dir;
  const std::string world = test::write_street_world(dir, 6);
  const std::vector<uint8_t> before = test::slurp(world);
  test::spit(dir.file("junk.cww"), {'h', 'i'});
  for (const std::string& args : {"stratify build " + dir.file("junk.cww"), "stratify build " + world + " --box 1e6",
                                  "stratify build " + world + " --resolution 0", "stratify build " + world + " --sizing foo",
                                  "stratify build " + world + " --alpha 0", "stratify build " + world + " --along " + dir.file("none.path"),
                                  "stratify build " + world + " --screen tall", "stratify build " + world + " --screen 480:0",
                                  "stratify build " + world + " --screen 4000:10", "stratify build " + world + " --screen 1080:0.00001",
                                  "stratify build " + world + " --screen inf", "stratify build " + world + " --screen 480 --resolution 64",
                                  "stratify build " + world + " --far-level-texels -1",
                                  "walk " + world + " --path " + test::source_path("tests/data/seeds/three.path") +
                                      " --strategy stratified:show=nothing"}) {
    const test::CommandResult r = test::run_cellwalk(args);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
  }
  EXPECT_EQ(test::slurp(world), before);
  // A world without the preprocessing: the strategy names the command that makes it.
  const test::CommandResult r =
      test::run_cellwalk("walk " + world + " --path " + test::source_path("tests/data/seeds/three.path") + " --strategy stratified");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("stratify build"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace cellwalk::stratified
