// The baseline every seed compares against: every object in the view frustum at full detail.
#pragma once

#include <memory>

#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

class BruteStrategy : public Strategy {
 public:
  // cull = false draws every object whatever the view: the fidelity harness's ground truth.
  BruteStrategy(const World& world, const StrategyOptions& options, bool cull);

  std::string name() const override { return cull_ ? "brute" : "ground-truth"; }
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  uint64_t resident_bytes() const override { return store_.resident_bytes(); }
  uint64_t peak_resident_bytes() const override { return store_.peak_resident_bytes(); }

 private:
  const World& world_;
  GeometryStore store_;
  bool cull_;
  std::shared_ptr<const Mesh> current_;  // the mesh handed to the renderer for upload
};

}  // namespace cellwalk
