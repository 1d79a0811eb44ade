// The baseline every seed compares against: every object in the view frustum at full detail.
#pragma once

#include <optional>

#include "cellwalk/strategy.hpp"

namespace cellwalk {

class BruteStrategy : public Strategy {
 public:
  // cull = false draws every object whatever the view: the fidelity harness's ground truth.
  BruteStrategy(const SceneReader& scene, bool cull);

  std::string name() const override { return cull_ ? "brute" : "ground-truth"; }
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  uint64_t resident_bytes() const override;

 private:
  const SceneReader& scene_;
  bool cull_;
  std::optional<Object> current_;  // the one object decoded for the renderer's upload
};

}  // namespace cellwalk
