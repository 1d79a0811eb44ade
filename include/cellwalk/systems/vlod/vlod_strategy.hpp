// vLOD (seed 001, Chhugani et al. 2003; digest 001): the walkthrough system whose run time keeps
// the current view cell's vLOD — its visible objects, each at the coarsest level whose error from
// anywhere in the cell is under the pixel bound — and changes it only by the Δ of each cell
// boundary it crosses, with the neighbours' additions prefetched (§2, §6; digest §3.8).
// The sets come from `cellwalk pvs WORLD --engine vlod` (precompute: the conservative engine on
// the levels each cell draws, src/precompute/engine_registry.cpp). Choices: docs/vlod.md.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

// Name: "vlod[:key=value,...]" with keys
//   cull=1       frustum-cull the vLOD each frame (0: draw all of it, the seed's silence)
//   prefetch=1   on entering a cell, prefetch the geometry its face neighbours add (0: none)
struct VlodConfig {
  bool cull = true;
  bool prefetch = true;
};
bool is_vlod_strategy_name(const std::string& name);
VlodConfig parse_vlod_strategy_name(const std::string& name);

// What the run did at cell boundaries (digest §5 "Coherence").
struct VlodCounters {
  uint64_t frames = 0;
  uint64_t cell_changes = 0;   // frames that entered another cell
  uint64_t crossings = 0;      // cell boundaries crossed, intermediate cells included
  uint64_t added = 0;          // Σ |A| over the changes: (object, level) pairs loaded
  uint64_t removed = 0;        // Σ |R|
  uint64_t prefetch_requests = 0;
  uint64_t section_bytes_read = 0;  // of the vlod section: key frames and Δ records read
  std::vector<double> delta_fractions;  // per change, |A| + |R| over |vLOD| of the new cell
};

class VlodStrategy : public Strategy {
 public:
  // Throws Error if the world has no vLOD sets (naming the command that makes them), or the
  // budget cannot hold the stored sets, the directory and the loads in flight.
  VlodStrategy(const World& world, const VlodConfig& config, const StrategyOptions& options);
  ~VlodStrategy() override;
  std::string name() const override;
  // Throws Error when the camera leaves the view cells, stands in a cell `pvs --along` skipped,
  // or renders larger or wider than the levels were chosen for (their bound would not hold).
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  bool serves_every_level() const override { return true; }
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  uint64_t resident_bytes() const override;
  uint64_t peak_resident_bytes() const override;
  const VlodCounters& counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
