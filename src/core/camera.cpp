#include "cellwalk/core/camera.hpp"

#include <glm/gtc/matrix_transform.hpp>

namespace cellwalk {

Vec3 Camera::forward() const {
  const float yaw = glm::radians(yaw_deg), pitch = glm::radians(pitch_deg);
  return {-std::sin(yaw) * std::cos(pitch), std::sin(pitch), -std::cos(yaw) * std::cos(pitch)};
}

Vec3 Camera::right() const {
  const float yaw = glm::radians(yaw_deg);
  return {std::cos(yaw), 0.0f, -std::sin(yaw)};
}

Vec3 Camera::up() const { return glm::cross(right(), forward()); }

Mat4 Camera::view() const { return glm::lookAt(position, position + forward(), up()); }

Mat4 Camera::projection() const {
  return glm::perspective(glm::radians(fov_y_deg), aspect, near_plane, far_plane);
}

Frustum::Frustum(const Mat4& m) {
  // Gribb & Hartmann: plane i is a row combination of the clip matrix (glm is column-major,
  // so row r is (m[0][r], m[1][r], m[2][r], m[3][r])).
  auto row = [&](int r) { return Vec4(m[0][r], m[1][r], m[2][r], m[3][r]); };
  const Vec4 w = row(3);
  planes_ = {w + row(0), w - row(0), w + row(1), w - row(1), w + row(2), w - row(2)};
  for (Vec4& p : planes_) p /= glm::length(Vec3(p));
}

Containment Frustum::classify(const Aabb& box) const {
  Containment result = Containment::kInside;
  for (const Vec4& p : planes_) {
    const Vec3 n(p);
    // The box corner furthest along the normal decides "outside"; the nearest, "inside".
    const Vec3 far_corner{n.x >= 0 ? box.max.x : box.min.x, n.y >= 0 ? box.max.y : box.min.y,
                          n.z >= 0 ? box.max.z : box.min.z};
    const Vec3 near_corner{n.x >= 0 ? box.min.x : box.max.x, n.y >= 0 ? box.min.y : box.max.y,
                           n.z >= 0 ? box.min.z : box.max.z};
    if (glm::dot(n, far_corner) + p.w < 0.0f) return Containment::kOutside;
    if (glm::dot(n, near_corner) + p.w < 0.0f) result = Containment::kIntersects;
  }
  return result;
}

}  // namespace cellwalk
