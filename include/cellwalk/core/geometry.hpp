// Vectors, matrices and axis-aligned boxes. World space is right-handed, Y up, metres; the
// ground is the plane y = 0.
#pragma once

#include <algorithm>
#include <limits>
#include <string>
#include <string_view>

#include <glm/glm.hpp>

namespace cellwalk {

using Vec2 = glm::vec2;
using Vec3 = glm::vec3;
using Vec4 = glm::vec4;
using Mat4 = glm::mat4;

// An axis-aligned bounding box. A default-constructed box is empty (min > max) and is the
// identity of extend().
struct Aabb {
  Vec3 min{std::numeric_limits<float>::max()};
  Vec3 max{std::numeric_limits<float>::lowest()};

  bool empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
  Vec3 center() const { return (min + max) * 0.5f; }
  Vec3 size() const { return max - min; }
  void extend(const Vec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void extend(const Aabb& b) {
    min = glm::min(min, b.min);
    max = glm::max(max, b.max);
  }
  bool contains(const Vec3& p) const {
    return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y && p.z >= min.z &&
           p.z <= max.z;
  }
  // True if `b` lies wholly inside this box (faces may touch).
  bool contains(const Aabb& b) const {
    return b.min.x >= min.x && b.min.y >= min.y && b.min.z >= min.z && b.max.x <= max.x &&
           b.max.y <= max.y && b.max.z <= max.z;
  }
  bool overlaps(const Aabb& b) const {
    return min.x <= b.max.x && b.min.x <= max.x && min.y <= b.max.y && b.min.y <= max.y &&
           min.z <= b.max.z && b.min.z <= max.z;
  }
};

// The largest |coordinate| of a position cellwalk accepts, in metres (issue 13, item 6): far
// beyond any city or ship, and small enough that every sum, difference and square of positions
// the pipeline forms (bounds, cell grids, path lengths, distances) stays finite in float.
constexpr float kMaxCoordinate = 1e7f;

// Throws Error "<where>: <what> (x, y, z) is not finite" or "... has a coordinate beyond 1e7 m",
// with what to do, unless every coordinate of `p` is finite and within ±kMaxCoordinate. Every
// reader of positions (model files, scene and world files, path generation) checks each with it.
void check_position(const Vec3& p, std::string_view where, const std::string& what);

// The box that holds `box` after the affine transform `m`.
Aabb transformed(const Aabb& box, const Mat4& m);

}  // namespace cellwalk
