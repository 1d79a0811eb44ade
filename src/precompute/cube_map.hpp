// ID cube maps: the six 90° views around a point rendered into object-id buffers, the
// "cubic projection" of HDoV thesis §5.5.2 (digest 000 §3.9). One mechanism for the DoV engine
// (256² per face at cell corners) and the ground truth (1024² per face at many points).
#pragma once

#include <array>
#include <memory>

#include "cellwalk/render/image.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk::visibility {

using CubeIds = std::array<IdImage, 6>;

// The largest face resolution a CubeMapRenderer accepts (an Error names anything outside
// [1, kMaxCubeResolution], before any GL work).
constexpr int kMaxCubeResolution = 8192;

// Renders on a thread of its own that owns the headless GL context, so any thread may call
// render(); calls are served one at a time (llvmpipe already uses every core per frame).
// Meshes are the world's level 0, decoded on demand and kept in the renderer's GPU cache.
class CubeMapRenderer {
 public:
  // Throws Error when no headless context can be made (e.g. Mesa's EGL is missing).
  CubeMapRenderer(const World& world, int resolution);
  ~CubeMapRenderer();

  int resolution() const { return resolution_; }
  // Faces in the order -Z, -X, +Z, +X, +Y, -Y; each resolution² ids (object id + 1, 0 for none).
  // Geometry nearer than 5 cm to p is clipped by the near plane.
  CubeIds render(const Vec3& p) const;

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
