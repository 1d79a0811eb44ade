// Tests of the screen-space error (src/lod/screen_error.cpp): known values, monotonicity,
// box distances, and the per-view-cell bound against an oracle that projects small vectors
// with the camera's own matrices from sampled viewpoints and view directions.
#include "cellwalk/lod/screen_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace cellwalk {
namespace {

const Lens kLens{glm::radians(60.0f), 4.0f / 3.0f, 1000.0f};

TEST(ScreenError, KnownValue) {
  // 1 m at 100 m, 60° vertical fov, 1000 px: 1000 / (2 · 100 · tan 30°) = 8.660 px.
  EXPECT_NEAR(screen_space_error(1.0f, 100.0f, kLens), 1000.0 / (200.0 * std::tan(M_PI / 6)), 1e-4);
  EXPECT_NEAR(focal_length_px(kLens), 866.0254, 1e-3);
  EXPECT_EQ(screen_space_error(0.0f, 0.0f, kLens), 0.0f);
  EXPECT_TRUE(std::isinf(pixels_per_unit(0.0f, kLens)));
  Camera camera;
  camera.fov_y_deg = 60.0f;
  EXPECT_NEAR(screen_space_error(1.0f, 100.0f, lens_of(camera, 1000.0f)), 8.660254, 1e-4);
}

TEST(ScreenError, DecreasesWithDistance) {
  float last = std::numeric_limits<float>::infinity();
  for (float d = 0.1f; d < 1000.0f; d *= 1.1f) {
    const float e = screen_space_error(0.01f, d, kLens);
    EXPECT_LT(e, last);
    last = e;
  }
}

TEST(ScreenError, BoxDistances) {
  const Aabb box{Vec3(0), Vec3(1)};
  EXPECT_EQ(distance_to_box(Vec3(0.5f), box), 0.0f);
  EXPECT_EQ(distance_to_box(Vec3(1.0f, 0.5f, 0.5f), box), 0.0f);
  EXPECT_FLOAT_EQ(distance_to_box(Vec3(3.0f, 0.5f, 0.5f), box), 2.0f);
  EXPECT_FLOAT_EQ(distance_to_box(Vec3(4.0f, 5.0f, 0.5f), box), 5.0f);  // 3-4-5 from a corner
  EXPECT_FLOAT_EQ(distance_between_boxes(box, {Vec3(4, 5, 0), Vec3(6, 6, 1)}), 5.0f);
  EXPECT_EQ(distance_between_boxes(box, {Vec3(0.5f), Vec3(2.0f)}), 0.0f);
  EXPECT_NEAR(max_off_axis_angle(kLens), std::atan(std::tan(M_PI / 6) * 5.0 / 3.0), 1e-6);
}

// The largest pixels-per-unit measured by projection: viewpoints sampled in the cell,
// points sampled in the object box, view directions turned so the point lands anywhere in
// the frustum (corners included), small displacements in random directions.
float sampled_max_pixels_per_unit(const Aabb& cell, const Aabb& object, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  auto in = [&](const Aabb& b) { return b.min + b.size() * Vec3(u(rng), u(rng), u(rng)); };
  const float width = kLens.viewport_height_px * kLens.aspect;
  float best = 0.0f;
  for (int i = 0; i < 20000; ++i) {
    Camera camera;
    camera.fov_y_deg = 60.0f;
    camera.aspect = kLens.aspect;
    camera.position = in(cell);
    const Vec3 q = in(object);
    const Vec3 to = q - camera.position;
    // yaw/pitch that look at q, then turned by up to the half fields of view
    const float yaw = glm::degrees(std::atan2(-to.x, -to.z)) + (u(rng) * 2 - 1) * 55.0f;
    const float pitch = glm::degrees(std::asin(to.y / glm::length(to))) + (u(rng) * 2 - 1) * 32.0f;
    camera.yaw_deg = yaw;
    camera.pitch_deg = std::clamp(pitch, -89.0f, 89.0f);
    const Mat4 vp = camera.view_projection();
    auto pixel = [&](const Vec3& p, bool& visible) {
      const Vec4 c = vp * Vec4(p, 1.0f);
      const Vec3 ndc = Vec3(c) / c.w;
      visible = c.w > 0 && std::abs(ndc.x) <= 1 && std::abs(ndc.y) <= 1;
      return Vec2((ndc.x + 1) * 0.5f * width, (ndc.y + 1) * 0.5f * kLens.viewport_height_px);
    };
    bool visible = false;
    const Vec2 p0 = pixel(q, visible);
    if (!visible) continue;
    const Vec3 dir = glm::normalize(Vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f));
    const float eps = 1e-3f * glm::length(to);
    bool unused = false;
    best = std::max(best, glm::length(pixel(q + eps * dir, unused) - p0) / eps);
  }
  return best;
}

TEST(ScreenError, CellBoundCoversEverySampledViewpoint) {
  std::mt19937 rng(3);
  const Aabb object{Vec3(-1, 0, -1), Vec3(1, 2, 1)};
  for (float gap : {0.5f, 2.0f, 10.0f, 50.0f}) {
    const Aabb cell{Vec3(1 + gap, 0, -2), Vec3(3 + gap, 2, 2)};
    const float bound = cell_pixels_per_unit(cell, object, kLens);
    const float sampled = sampled_max_pixels_per_unit(cell, object, rng);
    EXPECT_GE(bound * 1.01f, sampled) << "gap " << gap;
    EXPECT_LE(bound, 20.0f * sampled) << "gap " << gap;  // not uselessly loose either
    EXPECT_GE(bound, pixels_per_unit(distance_between_boxes(cell, object), kLens));
  }
}

// The bound is the corrected formula, f_px / (L_min cos² φ_max), exactly.
TEST(ScreenError, CellBoundFormula) {
  const Aabb object{Vec3(0), Vec3(1)};
  const Aabb cell{Vec3(4, 0, 0), Vec3(5, 1, 1)};  // L_min = 3
  const double t = std::tan(M_PI / 6) * std::sqrt(1 + 16.0 / 9.0);
  const double cos2 = 1.0 / (1.0 + t * t);
  EXPECT_NEAR(cell_pixels_per_unit(cell, object, kLens), 866.0254 / (3.0 * cos2), 1e-2);
  EXPECT_NEAR(cell_screen_space_error(0.01f, cell, object, kLens), 8.660254 / (3.0 * cos2), 1e-4);
  EXPECT_TRUE(std::isinf(cell_pixels_per_unit(object, object, kLens)));
  EXPECT_EQ(cell_screen_space_error(0.0f, object, object, kLens), 0.0f);
}

// The seed's text read literally (S = L cos²) grows with distance, the opposite of a
// projection: this is why kCorrected is the default (docs/lod.md).
TEST(ScreenError, FaithfulFormulaIsNotABound) {
  const Aabb object{Vec3(0), Vec3(1)};
  std::mt19937 rng(5);
  const Aabb near_cell{Vec3(2, 0, 0), Vec3(3, 1, 1)}, far_cell{Vec3(50, 0, 0), Vec3(51, 1, 1)};
  const auto faithful = CellBoundFormula::kFaithful;
  EXPECT_LT(cell_pixels_per_unit(near_cell, object, kLens, faithful),
            cell_pixels_per_unit(far_cell, object, kLens, faithful));
  EXPECT_LT(cell_pixels_per_unit(near_cell, object, kLens, faithful),
            sampled_max_pixels_per_unit(near_cell, object, rng));
}

}  // namespace
}  // namespace cellwalk
