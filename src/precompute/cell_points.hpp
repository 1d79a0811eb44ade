// Where a cell's visibility is sampled: its 8 corners (HDoV thesis §5.5.2 renders from them),
// face centres, centre, and random points inside and on its faces (vLOD §5 and the ground
// truth of issue 4). One place, so every engine and the ground truth mean the same points.
#pragma once

#include <vector>

#include "cellwalk/core/geometry.hpp"
#include "cellwalk/core/random.hpp"

namespace cellwalk::visibility {

std::vector<Vec3> cell_corners(const Aabb& box);
// 6 face centres then the centre.
std::vector<Vec3> cell_face_centres_and_centre(const Aabb& box);
// `count` random points: even ones uniform inside, odd ones uniform on a random face.
std::vector<Vec3> cell_random_points(const Aabb& box, int count, Random& rng);

}  // namespace cellwalk::visibility
