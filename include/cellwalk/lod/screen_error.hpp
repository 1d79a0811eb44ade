// Screen-space error of a level of detail: how many pixels an object-space error covers,
// from one viewpoint or, conservatively, from anywhere in a view cell.
// Seeds: 001 vLOD §2.2 (digest §3.2, the corrected per-view-cell bound and the faithful text
// behind a flag); 000 HDoV thesis §5.6 (LODs chosen by projected error).
#pragma once

#include "cellwalk/core/camera.hpp"
#include "cellwalk/core/geometry.hpp"

namespace cellwalk {

// What of a camera decides projected sizes: vertical field of view, width / height, and the
// viewport height in pixels.
struct Lens {
  float fov_y_rad = 1.0471976f;  // 60 degrees
  float aspect = 4.0f / 3.0f;
  float viewport_height_px = 1080.0f;
};

Lens lens_of(const Camera& camera, float viewport_height_px);

// f_px = (H_px / 2) / tan(fov_y / 2): the distance at which one object unit covers one pixel.
float focal_length_px(const Lens& lens);

// Pixels one object unit covers at `distance` on the view axis: f_px / distance.
// Infinite when distance <= 0 (the eye touches the object: only the finest level will do).
float pixels_per_unit(float distance, const Lens& lens);

// object_error · H_px / (2 · distance · tan(fov_y / 2)), the usual per-viewpoint measure.
float screen_space_error(float object_error, float distance, const Lens& lens);

// Euclidean distance from a point to a box; 0 inside or on it.
float distance_to_box(const Vec3& eye, const Aabb& box);
// Smallest distance between any point of `a` and any point of `b`; 0 when they overlap.
float distance_between_boxes(const Aabb& a, const Aabb& b);

// Largest angle between the view axis and a ray inside the frustum: the half-diagonal field
// of view, tan φ_max = tan(fov_y / 2) · sqrt(1 + aspect²).
float max_off_axis_angle(const Lens& lens);

enum class CellBoundFormula {
  // Digest §3.2 [ours]: the largest magnification of any small object-space vector in
  // `object`, seen from any viewpoint in the cell in any view direction that keeps it in the
  // frustum, is f_px / (L_min · cos² φ_max). Tight: reached at the frustum's corner.
  kCorrected,
  // The paper's text as written: S = L_min · cos²(FOV) taken as pixels per unit. It grows
  // with distance, so it is not a bound; kept only to reproduce the seed (docs/lod.md).
  kFaithful,
};

// Pixels per object unit that bound the projection of `object` from anywhere in `cell`
// (L_min = distance_between_boxes(cell, object)). Infinite when L_min = 0 (kCorrected).
float cell_pixels_per_unit(const Aabb& cell, const Aabb& object, const Lens& lens,
                           CellBoundFormula formula = CellBoundFormula::kCorrected);

// object_error · cell_pixels_per_unit(...): the worst screen-space error over the cell.
float cell_screen_space_error(float object_error, const Aabb& cell, const Aabb& object,
                              const Lens& lens,
                              CellBoundFormula formula = CellBoundFormula::kCorrected);

}  // namespace cellwalk
