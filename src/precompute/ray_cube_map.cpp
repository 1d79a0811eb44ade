// ID cube maps from Embree primary rays through pixel centres (HDoV thesis §5.5.2, digest 000
// §3.9): the `rays` mode of the DoV engine, checked against the GL path by
// DovEngine/DovCubesAgainstExact.
#include "precompute/ray_cube_map.hpp"

#include <tbb/parallel_for.h>

namespace cellwalk::visibility {

RayCubeMap::RayCubeMap(const World& world, std::shared_ptr<const EmbreeScene> scene, int resolution)
    : scene_(std::move(scene)), resolution_(checked_cube_resolution(resolution)), far_plane_(cube_far_plane(world)) {}

CubeIds RayCubeMap::render(const Vec3& p) const {
  const int r = resolution_;
  CubeIds out;
  std::array<Camera, 6> cameras;
  for (size_t f = 0; f < 6; ++f) {
    out[f] = IdImage{r, r, std::vector<uint32_t>(size_t(r) * r, kBackgroundId)};
    cameras[f] = cube_face_camera(p, f, far_plane_);
  }
  // One task per face row: a row's rays are coherent, and 6·r tasks keep every core busy.
  tbb::parallel_for(size_t(0), size_t(6) * r, [&](size_t task) {
    const size_t f = task / size_t(r);
    const int j = int(task % size_t(r));
    const Camera& c = cameras[f];
    const Vec3 forward = c.forward(), right = c.right(), up = c.up();
    // The pixel centre's direction with a view-axis component of 1: t is the view depth, so
    // the near and far planes clip as the GL projection's do.
    const float y = float(2 * j + 1) / float(r) - 1.0f;
    std::vector<Vec3> dirs(static_cast<size_t>(r));
    for (int i = 0; i < r; ++i) dirs[size_t(i)] = forward + (float(2 * i + 1) / float(r) - 1.0f) * right + y * up;
    scene_->first_hits(p, dirs, kCubeNearPlane, far_plane_,
                       std::span<uint32_t>(out[f].ids).subspan(size_t(j) * size_t(r), size_t(r)));
  });
  return out;
}

}  // namespace cellwalk::visibility
