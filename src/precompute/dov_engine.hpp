// The degree-of-visibility engine of HDoV thesis §5.5.2 (digest 000 §3.9): ID cube maps at the
// cell's 8 corners, pixel weights of eq. 5.11, the maximum over corners as the cell's DoV.
#pragma once

#include <memory>
#include <unordered_map>

#include "cellwalk/precompute/engine.hpp"
#include "precompute/cube_map.hpp"
#include "precompute/embree_scene.hpp"

namespace cellwalk::visibility {

class DovEngine : public VisibilityEngine {
 public:
  // `prior` (optional, e.g. the sampling or conservative engine; it must outlive this) is the
  // thesis's step 1: objects it finds visible that cover no pixel get DoV_s, the smallest pixel
  // weight, so they are still drawn. Without it the set is the objects that cover pixels.
  // The cube maps come from options.dov_cubes; `scene` (optional) is `world`'s level-0 Embree
  // scene for the rays mode when the caller already holds one.
  DovEngine(const World& world, const EngineOptions& options, const VisibilityEngine* prior = nullptr,
            std::shared_ptr<const EmbreeScene> scene = nullptr);
  ~DovEngine() override;
  std::string name() const override { return "dov"; }
  bool conservative() const override { return false; }
  VisibleSet compute(const ViewCell& cell) const override;

  // Point DoVs at the 8 corners (objects with pixels at some corner), for group_dov().
  CornerDov compute_corners(const ViewCell& cell) const;

 private:
  using PointDov = std::unordered_map<ObjectId, double>;
  struct CornerCache;

  // The point DoV at p, from the cache when a neighbouring cell has computed it.
  std::shared_ptr<const PointDov> point_dov(const Vec3& p) const;

  const VisibilityEngine* prior_;
  std::unique_ptr<CubeMapSource> cube_;
  std::vector<double> weights_;
  double smallest_;
  // Cells of a partition share corners bit for bit (a grid corner belongs to up to 8 cells), so
  // the fast modes keep the latest corners' point DoVs. Null in exact mode, which stays the
  // reference as it was: one cube map per corner of every cell.
  std::unique_ptr<CornerCache> cache_;
};

// The cube-map source of `cubes` at `resolution` over `world` (`scene` as for DovEngine).
std::unique_ptr<CubeMapSource> make_cube_maps(DovCubes cubes, const World& world, int resolution,
                                              std::shared_ptr<const EmbreeScene> scene = nullptr);

}  // namespace cellwalk::visibility
