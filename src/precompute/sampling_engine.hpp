// The sampling visibility engine: Embree rays from many points of a cell over the whole
// sphere and aimed at every object's box (vLOD §5 samples; HDoV thesis §5.5.2 uses the 8
// corners). Fast and aggressive: an
// object seen only through a gap no ray passes is missed, so it is not conservative.
#pragma once

#include <memory>

#include "cellwalk/precompute/engine.hpp"
#include "precompute/embree_scene.hpp"

namespace cellwalk::visibility {

class SamplingEngine : public VisibilityEngine {
 public:
  // `scene` (optional) is `world`'s level-0 Embree scene when the caller already holds one.
  SamplingEngine(const World& world, const EngineOptions& options, std::shared_ptr<const EmbreeScene> scene = nullptr);
  std::string name() const override { return "sampling"; }
  bool conservative() const override { return false; }
  // Deterministic: the random points and direction rotations are seeded from the cell's box.
  VisibleSet compute(const ViewCell& cell) const override;

 private:
  const World& world_;
  EngineOptions options_;
  std::shared_ptr<const EmbreeScene> scene_;
  std::vector<Vec3> directions_;  // a Fibonacci sphere, rotated per point
  float far_;
};

}  // namespace cellwalk::visibility
