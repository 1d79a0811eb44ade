// Li & Chiang (seed 003, ISMIP 1999): the walkthrough system of visible sets per viewpoint
// configuration, prioritized prefetching by a relevance matrix, and the hybrid cache. Each
// frame: find the configuration (view cell, yaw sector); draw the union of the sets of its
// 1-neighbours ("Visibility Pre-computation": the conservative approach); fetch what is not
// resident (t_c, a stall); then hand the neighbouring configurations' objects to a loader
// thread in relevance order (t_p: it runs while the frame draws, and what it has not started
// when the viewer's configuration or motion changes is dropped, with a bound on loads in
// flight). The cache is LRU across frames and by relevance within one ("Hybrid Cache Model").
// The sets are the stored from-region sets of `cellwalk pvs` over grid cells (any engine but vlod).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

// Name: "lichiang[:key=value,...]" with keys
//   cache=hybrid       hybrid (LRU across frames, relevance within one; a prefetch evicts only
//                      what that order puts before it), lru, or none (nothing is kept from one
//                      frame to the next: the seed's case 1, with prefetch=none)
//   prefetch=relevance relevance (the relevance matrix's window, most relevant first), one-step
//                      (the configuration the viewer moves into next, [Chim 98]), or none
//   sectors=8          orientation sectors of a configuration (1: position only)
//   neighbours=1       draw the union of the 1-neighbours' sets, as the seed (0: the own set)
//   cull=1             frustum-cull what is drawn (0: draw the whole union)
//   tp_ms=T            the seed's frame cycle t_c + t_g + t_p: after each frame, prefetch on the
//                      frame's own thread for T ms (a load once started ends); without tp_ms or
//                      frame_ms the loader thread runs beside the frames
//   frame_ms=F         as tp_ms, with t_p = F − (t_c + t_g) of the frame just drawn, at least 0
// The seed's four cases: cache=none,prefetch=none; cache=lru,prefetch=none;
// cache=lru,prefetch=one-step; cache=hybrid,prefetch=relevance (the default).
struct LiChiangConfig {
  enum class Cache { kNone, kLru, kHybrid };
  enum class Prefetch { kNone, kOneStep, kRelevance };
  Cache cache = Cache::kHybrid;
  Prefetch prefetch = Prefetch::kRelevance;
  int sectors = 8;
  bool neighbours = true;
  bool cull = true;
  // t_p on the frame's thread (the seed's cycle): a fixed allowance, or what is left of a frame
  // budget. Both < 0: the loader thread runs beside the frames instead.
  double tp_ms = -1.0;
  double frame_ms = -1.0;
  bool prefetch_in_frame() const { return tp_ms >= 0.0 || frame_ms >= 0.0; }
};
bool is_lichiang_strategy_name(const std::string& name);
LiChiangConfig parse_lichiang_strategy_name(const std::string& name);

struct LiChiangCounters {
  uint64_t frames = 0;
  uint64_t configuration_changes = 0;  // frames whose (cell, sector) differs from the last's
  uint64_t plans = 0;                  // prefetch plans made (configuration or motion changed)
  uint64_t prefetch_requests = 0;      // objects handed to the loader thread
  uint64_t drawn_ids = 0;              // Σ over frames of the union drawn (before culling)
  uint64_t own_ids = 0;                // Σ over frames of the configuration's own set
  double prefetch_ms = 0.0;            // Σ t_p spent prefetching on the frame's thread (tp_ms, frame_ms)
};

class LiChiangStrategy : public Strategy {
 public:
  // Throws Error if the world has no stored sets over a grid (naming the command that makes
  // them), or the budget cannot hold them beside the directory and the loads in flight.
  LiChiangStrategy(const World& world, const LiChiangConfig& config, const StrategyOptions& options);
  ~LiChiangStrategy() override;
  std::string name() const override;
  // Throws Error when the camera stands in a cell `pvs --along` skipped.
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  uint64_t resident_bytes() const override;
  uint64_t peak_resident_bytes() const override;
  const LiChiangCounters& counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
