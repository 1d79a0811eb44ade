// Stratified rendering (seed 002, Xiong 1996) §3.2, §5.1, §5.2 (digest 002 §2.2, §3.7): the
// walkthrough system. Each frame: find the viewcell holding the eye; on entering a new one, load
// its near list and far faces; draw the far faces as background and the near objects as
// polygons (frustum culled). The cells and faces come from `cellwalk stratify build`.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

// Name: "stratified[:key=value,...]" with keys
//   show=full         the thesis's show styles (§5.1): full (near polygons + far faces), near
//                     (near objects only), far-objects (the far objects as polygons, nothing
//                     near), far-texture (the far faces only), brute (every object)
//   cull=1            frustum-cull the objects drawn as polygons (0: draw them all)
//   prefetch=1        load the cells the viewer is heading for on a thread of their own, from its
//                     velocity (the thesis's future work, §7), so a crossing finds them ready
//                     (0: every crossing loads in its frame, as the thesis's did)
//   lookahead=1.5     seconds of motion ahead whose cells are prefetched
//   fade=0            frames over which the previous cell's far faces fade out after a crossing,
//                     blended over the new cell's, to hide the far field's jump of up to 2α
//                     (digest §3.7; 0: the thesis's hard switch)
struct StratifiedConfig {
  enum class Show { kFull, kNear, kFarObjects, kFarTexture, kBrute };
  Show show = Show::kFull;
  bool cull = true;
  bool prefetch = true;
  double lookahead_s = 1.5;
  int fade_frames = 0;
};
bool is_stratified_strategy_name(const std::string& name);
StratifiedConfig parse_stratified_strategy_name(const std::string& name);

// What the run did at cell boundaries (digest §3.7, Table 3.1).
struct StratifiedCounters {
  uint64_t frames = 0;
  uint64_t crossings = 0;       // frames that entered another cell
  uint64_t loaded_bytes = 0;    // far-field records read, by the frames and the prefetcher
  double load_ms = 0.0;         // reading and decoding them
  uint64_t near_objects = 0;    // Σ over frames of the current cell's near list
  uint64_t prefetched = 0;      // cells loaded ahead by the prefetcher
  uint64_t prefetch_hits = 0;   // crossings that found their cell loaded
  uint64_t stalls = 0;          // crossings (after the first frame) that had to load or wait for their cell
  uint64_t faded_frames = 0;    // frames that drew a previous cell's faces fading out
};

class StratifiedStrategy : public Strategy {
 public:
  // Throws Error if the world has no stratified preprocessing (naming the command that makes it)
  // or the budget cannot hold the geometry store and the stored cells; select() throws when it
  // cannot hold the load of a cell it enters (its load bound: record, six decoded faces, near list).
  StratifiedStrategy(const World& world, const StratifiedConfig& config, const StrategyOptions& options);
  ~StratifiedStrategy() override;
  std::string name() const override;
  // Throws Error when the camera leaves the viewcells or stands in a cell `--along` left unbaked.
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  bool serves_every_level() const override { return true; }
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  std::span<const FarFace> far_faces() const override;
  // The current viewcell in cyan and its bounding box in white (the thesis's bird's-eye view,
  // Fig. 5-2).
  void overlay(std::vector<LineSegment>& lines) const override;
  uint64_t resident_bytes() const override;
  uint64_t peak_resident_bytes() const override;
  const StratifiedCounters& counters() const;
  // The far field's angular error from `camera` (far_field_angle on the current cell's faces),
  // radians; 0 before the first select() or in a show style without faces.
  double far_angle(const Camera& camera) const;
  // Whether the last select() entered another cell (and so loaded its far field).
  bool crossed() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
