// ID cube maps: the six 90° views around a point as object-id buffers, the "cubic projection"
// of HDoV thesis §5.5.2 (digest 000 §3.9). One layout for every source: the GL renderer (the DoV
// engine's exact mode and the ground truth) and Embree rays (ray_cube_map.hpp, the rays mode).
#pragma once

#include <array>
#include <memory>

#include "cellwalk/core/camera.hpp"
#include "cellwalk/render/image.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk::visibility {

using CubeIds = std::array<IdImage, 6>;

// The largest face resolution a cube map accepts (an Error names anything outside
// [1, kMaxCubeResolution], before any GL or Embree work).
constexpr int kMaxCubeResolution = 8192;

// Geometry nearer than this to the cube's centre along a face's view axis is clipped.
constexpr float kCubeNearPlane = 0.05f;

// The camera of face `face` (0..5 in the order -Z, -X, +Z, +X, +Y, -Y) at p: 90° square view,
// near plane kCubeNearPlane. Pixel (i, j) of a face (row j from the bottom, as GL reads it
// back) is centred on the view direction forward + x·right + y·up, x = (2i + 1)/R - 1,
// y = (2j + 1)/R - 1.
Camera cube_face_camera(const Vec3& p, size_t face, float far_plane);
// A far plane beyond every object of `world` seen from anywhere in its bounds.
float cube_far_plane(const World& world);
// `resolution` if it lies in [1, kMaxCubeResolution]; else throws Error saying so.
int checked_cube_resolution(int resolution);

// A source of ID cube maps. Faces in the order -Z, -X, +Z, +X, +Y, -Y; each resolution² ids
// (object id + 1, 0 for none), row-major from the bottom row. Thread-safety: render() may be
// called concurrently.
class CubeMapSource {
 public:
  virtual ~CubeMapSource() = default;
  virtual int resolution() const = 0;
  virtual CubeIds render(const Vec3& p) const = 0;
};

// Renders on a thread of its own that owns the headless GL context, so any thread may call
// render(); calls are served one at a time (llvmpipe already uses every core per frame).
// Meshes are the world's level 0, decoded on demand and kept in the renderer's GPU cache.
class CubeMapRenderer : public CubeMapSource {
 public:
  // Throws Error when no headless context can be made (e.g. Mesa's EGL is missing).
  CubeMapRenderer(const World& world, int resolution);
  ~CubeMapRenderer() override;

  int resolution() const override { return resolution_; }
  // Every object whose box meets a face's frustum, at level 0: the reference every other
  // source is checked against.
  CubeIds render(const Vec3& p) const override;

 private:
  struct Impl;
  int resolution_;
  std::unique_ptr<Impl> impl_;
};

// The solid angle of each pixel of a cube face of `resolution`² pixels, divided by 4π (eq.
// 5.11). Integrated exactly over the pixel, the six faces sum to 1; `midpoint` gives the
// thesis's form at pixel centres instead (sums to 1 - O(1/resolution²)). Row-major; the same
// for every face (the weights are symmetric, so the image's row order does not matter).
std::vector<double> cube_pixel_weights(int resolution, bool midpoint = false);

}  // namespace cellwalk::visibility
