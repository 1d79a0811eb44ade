// Ground-truth visible sets: union of ID cube maps from the cell's corners and random points
// inside and on its faces (issue 4's check; the cube maps of HDoV thesis §5.5.2 at high
// resolution).
#include "visibility/ground_truth.hpp"

#include <algorithm>

#include "visibility/cell_points.hpp"

namespace cellwalk::visibility {

std::vector<ObjectId> ground_truth_visible(const CubeMapRenderer& cube, const ViewCell& cell,
                                           const GroundTruthOptions& options) {
  Random rng(options.seed ^ (uint64_t(cell.id) * 0x9E3779B97F4A7C15ull));
  std::vector<Vec3> points = cell_corners(cell.box);
  for (const Vec3& p : cell_random_points(cell.box, options.points, rng)) points.push_back(p);
  std::vector<bool> seen;
  for (const Vec3& p : points)
    for (const IdImage& face : cube.render(p))
      for (uint32_t id : face.ids) {
        if (id == kBackgroundId) continue;
        if (id > seen.size()) seen.resize(id, false);
        seen[id - 1] = true;
      }
  std::vector<ObjectId> out;
  for (size_t i = 0; i < seen.size(); ++i)
    if (seen[i]) out.push_back(ObjectId(i));
  return out;
}

}  // namespace cellwalk::visibility
