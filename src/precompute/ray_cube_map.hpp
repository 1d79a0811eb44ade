// ID cube maps by ray casting: one Embree primary ray through each pixel centre of each face,
// in the GL path's face orientation, order and pixel layout, with its near and far planes
// (HDoV thesis §5.5.2's cubic projection, digest 000 §3.9; the `rays` mode of the DoV engine).
// A rasteriser samples coverage at the same pixel centres, so the two agree except where a
// centre falls within rounding of an edge or two surfaces lie within depth precision.
#pragma once

#include <memory>

#include "precompute/cube_map.hpp"
#include "precompute/embree_scene.hpp"

namespace cellwalk::visibility {

class RayCubeMap : public CubeMapSource {
 public:
  // `scene` holds `world`'s level-0 meshes (geometry id = object id). Throws Error on a
  // resolution outside [1, kMaxCubeResolution].
  RayCubeMap(const World& world, std::shared_ptr<const EmbreeScene> scene, int resolution);

  int resolution() const override { return resolution_; }
  // Rows of all six faces in parallel (TBB); thread-safe.
  CubeIds render(const Vec3& p) const override;

 private:
  std::shared_ptr<const EmbreeScene> scene_;
  int resolution_;
  float far_plane_;
};

}  // namespace cellwalk::visibility
