// How much of each frame of a camera path shows the world, by rays (issue 16: a path for any
// world must keep the model in view; `cellwalk path` reports it).
#include <algorithm>
#include <cmath>

#include "cellwalk/precompute/path_planner.hpp"
#include "precompute/embree_scene.hpp"

namespace cellwalk {

std::vector<float> view_coverage(const World& world, const CameraPath& path, const Camera& lens, int columns) {
  const visibility::EmbreeScene scene(world);
  const int rows = std::max(1, int(std::lround(columns / lens.aspect)));
  const float tan_y = std::tan(glm::radians(lens.fov_y_deg) / 2), tan_x = tan_y * lens.aspect;
  std::vector<Vec3> dirs(size_t(columns) * rows);
  std::vector<uint32_t> ids(dirs.size());
  std::vector<float> coverage;
  coverage.reserve(path.frames.size());
  for (const PathFrame& frame : path.frames) {
    Camera cam = lens;
    apply(frame, cam);
    const Vec3 f = cam.forward(), r = cam.right(), u = cam.up();
    // Pixel centres of a columns × rows image; each direction is 1 along the view axis, so the
    // near and far planes clip as a projection does.
    for (int y = 0; y < rows; ++y)
      for (int x = 0; x < columns; ++x)
        dirs[size_t(y) * columns + x] =
            f + r * (tan_x * ((x + 0.5f) / columns * 2 - 1)) + u * (tan_y * (1 - (y + 0.5f) / rows * 2));
    scene.first_hits(cam.position, dirs, cam.near_plane, cam.far_plane, ids);
    coverage.push_back(float(std::count_if(ids.begin(), ids.end(), [](uint32_t id) { return id != 0; })) / float(ids.size()));
  }
  return coverage;
}

}  // namespace cellwalk
