// Screen-space error of LODs from a viewpoint and from a view cell.
// Seed: 001 vLOD §2.2 (digest §3.2: the corrected per-cell bound, the faithful text behind
// CellBoundFormula::kFaithful).
#include "cellwalk/lod/screen_error.hpp"

#include <cmath>
#include <limits>

namespace cellwalk {

Lens lens_of(const Camera& camera, float viewport_height_px) {
  return {glm::radians(camera.fov_y_deg), camera.aspect, viewport_height_px};
}

float focal_length_px(const Lens& lens) {
  return 0.5f * lens.viewport_height_px / std::tan(0.5f * lens.fov_y_rad);
}

float pixels_per_unit(float distance, const Lens& lens) {
  if (distance <= 0.0f) return std::numeric_limits<float>::infinity();
  return focal_length_px(lens) / distance;
}

float screen_space_error(float object_error, float distance, const Lens& lens) {
  // A zero error stays zero even at distance 0 (0 · inf would be NaN).
  if (object_error <= 0.0f) return 0.0f;
  return object_error * pixels_per_unit(distance, lens);
}

float distance_to_box(const Vec3& eye, const Aabb& box) {
  const Vec3 outside = glm::max(glm::max(box.min - eye, eye - box.max), Vec3(0.0f));
  return glm::length(outside);
}

float distance_between_boxes(const Aabb& a, const Aabb& b) {
  // Per axis, the gap between the intervals (0 when they overlap).
  const Vec3 gap = glm::max(glm::max(b.min - a.max, a.min - b.max), Vec3(0.0f));
  return glm::length(gap);
}

float max_off_axis_angle(const Lens& lens) {
  const float t = std::tan(0.5f * lens.fov_y_rad);
  return std::atan(t * std::sqrt(1.0f + lens.aspect * lens.aspect));
}

float cell_pixels_per_unit(const Aabb& cell, const Aabb& object, const Lens& lens,
                           CellBoundFormula formula) {
  const float l_min = distance_between_boxes(cell, object);
  const float c = std::cos(max_off_axis_angle(lens));
  if (formula == CellBoundFormula::kFaithful) return l_min * c * c;
  // At off-axis angle φ a point at distance L has depth d = L cos φ; the projection's
  // Jacobian there has largest singular value f / (d cos φ) = f / (L cos² φ).
  if (l_min <= 0.0f) return std::numeric_limits<float>::infinity();
  return focal_length_px(lens) / (l_min * c * c);
}

float cell_screen_space_error(float object_error, const Aabb& cell, const Aabb& object,
                              const Lens& lens, CellBoundFormula formula) {
  if (object_error <= 0.0f) return 0.0f;
  return object_error * cell_pixels_per_unit(cell, object, lens, formula);
}

}  // namespace cellwalk
