// Stratified rendering (seed 002) §3.1.2: far-field baking in parallel within one process (the
// thesis baked one cell after another; issue 17 asks for parallel baking). Each thread has a
// FarFieldBaker, and so a headless GL context, of its own, and encodes what it bakes (the
// compression costs about as much as the drawing); the records come out in job order, so a
// pooled bake writes the same bytes as one baker.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/far_field.hpp"
#include "cellwalk/systems/stratified/stored_stratified.hpp"

namespace cellwalk::stratified {

// One cell to bake: its centre, its box side and its near list (ascending ids; the span must
// stay valid while the pool lives).
struct BakeJob {
  Vec3 centre{0.0f};
  float b = 0.0f;
  std::span<const ObjectId> near;
};

// Thread-safety: next() and triangles_drawn() from the owning thread only.
class BakePool {
 public:
  // Starts `threads` (≥ 1) workers that bake `jobs` in order, at most 2·threads cells ahead of
  // the ones taken. `world` must outlive the pool.
  BakePool(const World& world, const BakeSettings& settings, int threads, std::vector<BakeJob> jobs);
  ~BakePool();  // stops the workers (a cell being baked is finished first)
  BakePool(const BakePool&) = delete;
  BakePool& operator=(const BakePool&) = delete;
  // The next job's far-field record (encode_far_field's bytes). REQUIRES: fewer calls than
  // jobs. Once a worker has failed (a bad setting, no GL context, a damaged object), gives the
  // records already baked in order and then rethrows its Error.
  std::vector<uint8_t> next();
  // Triangles drawn by the cells baked so far.
  uint64_t triangles_drawn() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk::stratified
