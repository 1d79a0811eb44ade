#include "cellwalk/core/geometry.hpp"

#include <cmath>
#include <cstdio>

#include "cellwalk/core/error.hpp"

namespace cellwalk {

static_assert(kMaxCoordinate == 1e7f, "check_position's message names the bound");

void check_position(const Vec3& p, std::string_view where, const std::string& what) {
  const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  if (finite && std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate &&
      std::abs(p.z) <= kMaxCoordinate)
    return;
  char at[96];
  std::snprintf(at, sizeof at, "(%g, %g, %g)", double(p.x), double(p.y), double(p.z));
  fail(where, what + " " + at +
                  (finite ? " has a coordinate beyond 1e7 m, the largest cellwalk handles; rescale the model "
                            "(e.g. to metres) or move it nearer the origin"
                          : " is not finite; fix or remove it in the model"));
}

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
