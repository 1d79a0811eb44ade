// The degree-of-visibility engine of HDoV thesis §5.5.2 (digest 000 §3.9): ID cube maps at the
// cell's 8 corners, pixel weights of eq. 5.11, the maximum over corners as the cell's DoV.
#pragma once

#include "cellwalk/precompute/engine.hpp"
#include "precompute/cube_map.hpp"

namespace cellwalk::visibility {

class DovEngine : public VisibilityEngine {
 public:
  // `prior` (optional, e.g. the sampling or conservative engine; it must outlive this) is the
  // thesis's step 1: objects it finds visible that cover no pixel get DoV_s, the smallest pixel
  // weight, so they are still drawn. Without it the set is the objects that cover pixels.
  DovEngine(const World& world, const EngineOptions& options, const VisibilityEngine* prior = nullptr);
  std::string name() const override { return "dov"; }
  bool conservative() const override { return false; }
  VisibleSet compute(const ViewCell& cell) const override;

  // Point DoVs at the 8 corners (objects with pixels at some corner), for group_dov().
  CornerDov compute_corners(const ViewCell& cell) const;

 private:
  const VisibilityEngine* prior_;
  CubeMapRenderer cube_;
  std::vector<double> weights_;
  double smallest_;
};

}  // namespace cellwalk::visibility
