// Sample points of a view cell: corners (HDoV thesis §5.5.2), face centres, centre, random
// points inside and on the faces (vLOD §5; ground truth of docs/visibility.md).
#include "precompute/cell_points.hpp"

namespace cellwalk::visibility {

std::vector<Vec3> cell_corners(const Aabb& b) {
  std::vector<Vec3> out;
  for (int k = 0; k < 8; ++k)
    out.emplace_back(k & 1 ? b.max.x : b.min.x, k & 2 ? b.max.y : b.min.y, k & 4 ? b.max.z : b.min.z);
  return out;
}

std::vector<Vec3> cell_face_centres_and_centre(const Aabb& b) {
  std::vector<Vec3> out;
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {b.min[axis], b.max[axis]}) {
      Vec3 p = b.center();
      p[axis] = side;
      out.push_back(p);
    }
  out.push_back(b.center());
  return out;
}

std::vector<Vec3> cell_random_points(const Aabb& b, int count, Random& rng) {
  std::vector<Vec3> out;
  for (int i = 0; i < count; ++i) {
    Vec3 p;
    for (int a = 0; a < 3; ++a) p[a] = float(rng.uniform(b.min[a], b.max[a]));
    if (i % 2 == 1) {
      const int face = int(rng.integer(0, 5));
      p[face / 2] = face % 2 ? b.max[face / 2] : b.min[face / 2];
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace cellwalk::visibility
