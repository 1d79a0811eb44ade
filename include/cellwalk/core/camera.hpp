// The perspective camera of a walkthrough and its view frustum.
#pragma once

#include <array>

#include "cellwalk/core/geometry.hpp"

namespace cellwalk {

// Orientation is yaw and pitch in degrees: yaw 0 looks along -Z, yaw 90 along -X (turning
// left), pitch positive looks up. Walkthroughs need no roll.
struct Camera {
  Vec3 position{0.0f};
  float yaw_deg = 0.0f;
  float pitch_deg = 0.0f;
  float fov_y_deg = 60.0f;
  float aspect = 4.0f / 3.0f;
  float near_plane = 0.25f;
  float far_plane = 5000.0f;

  Vec3 forward() const;
  Vec3 right() const;
  Vec3 up() const;
  Mat4 view() const;
  Mat4 projection() const;
  Mat4 view_projection() const { return projection() * view(); }
};

enum class Containment { kOutside, kIntersects, kInside };

// Six planes, normals pointing inwards: a point p is inside when dot(n, p) + d >= 0 for all.
class Frustum {
 public:
  explicit Frustum(const Mat4& view_projection);
  explicit Frustum(const Camera& camera) : Frustum(camera.view_projection()) {}

  // Conservative: kOutside only if the box is entirely outside one plane.
  Containment classify(const Aabb& box) const;
  bool intersects(const Aabb& box) const { return classify(box) != Containment::kOutside; }
  const std::array<Vec4, 6>& planes() const { return planes_; }

 private:
  std::array<Vec4, 6> planes_;
};

}  // namespace cellwalk
