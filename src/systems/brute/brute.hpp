// The baselines every seed compares against: every object in the view frustum at full detail
// (`brute`), every object whatever the view (`ground-truth`), and frustum culling with each
// object at the coarsest level whose screen-space error is under a pixel bound (`lod`, the
// honest "frustum culling + LOD" baseline; the bound is vLOD's corrected one, digest §3.2,
// taken from the eye: a level chosen for < 1 px is < 1 px anywhere in the image).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "cellwalk/lod/screen_error.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

// lod[:px=P]: the screen-space error bound, pixels (default 1).
struct LodBaselineConfig {
  float max_px = 1.0f;
};
bool is_lod_strategy_name(const std::string& name);
LodBaselineConfig parse_lod_strategy_name(const std::string& name);

class BruteStrategy : public Strategy {
 public:
  // cull = false draws every object whatever the view: the fidelity harness's ground truth.
  // `lod` set: levels by screen-space error (REQUIRES options.viewport_height_px > 0, else
  // Error). Culling is then always on.
  BruteStrategy(const World& world, const StrategyOptions& options, bool cull,
                std::optional<LodBaselineConfig> lod = std::nullopt);

  std::string name() const override { return lod_ ? "lod" : cull_ ? "brute" : "ground-truth"; }
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  bool serves_every_level() const override { return true; }
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  uint64_t resident_bytes() const override { return store_.resident_bytes(); }
  uint64_t peak_resident_bytes() const override { return store_.peak_resident_bytes(); }

 private:
  const World& world_;
  GeometryStore store_;
  bool cull_;
  std::optional<LodBaselineConfig> lod_;
  float viewport_height_px_;
  std::shared_ptr<const Mesh> current_;  // the mesh handed to the renderer for upload
};

}  // namespace cellwalk
