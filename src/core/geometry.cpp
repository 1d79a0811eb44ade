#include "cellwalk/core/geometry.hpp"

namespace cellwalk {

Aabb transformed(const Aabb& box, const Mat4& m) {
  Aabb out;
  if (box.empty()) return out;
  for (int corner = 0; corner < 8; ++corner) {
    Vec3 p{(corner & 1) ? box.max.x : box.min.x, (corner & 2) ? box.max.y : box.min.y,
           (corner & 4) ? box.max.z : box.min.z};
    out.extend(Vec3(m * Vec4(p, 1.0f)));
  }
  return out;
}

}  // namespace cellwalk
