// A VDR client walked along a camera path, measured as the thesis measured it (seed 004, §4.6,
// §5.5, §6.4; digest §5 "Metrics"): per frame T_u, T_r and the frame time, triangles, updates,
// unmodified frames, and every few frames the accuracy against a reference — the sequential
// run with the true view parameters (the traversal run locally, each frame's batch applied at
// once) — as |T ∩ T_ref| / |T_ref|, a triangle being its three full-model vertex ids.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "cellwalk/systems/vdr/vdr_client.hpp"
#include "cellwalk/systems/vdr/vdr_file.hpp"
#include "cellwalk/systems/vdr/vdr_paths.hpp"

namespace cellwalk::vdr {

// The reference run: the same traversal, B, N, τ and α, one batch per frame for the true view,
// in BUDGET mode above the alarm level B − 2N. Thread-safety: none.
class ReferenceWalk {
 public:
  // REQUIRES: `model` outlives this.
  ReferenceWalk(const VdrModel& model, const Hello& hello, const VdrClientOptions& options);
  ~ReferenceWalk();
  // One batch for the view, in BUDGET mode above the alarm level B − 2N·in_flight.
  const SelectiveMesh& step(const Vec3& eye, const Vec3& aim, uint32_t in_flight = 1);
  // Steps on the one view until a step changes nothing (true) or options.prime_batches steps
  // (false): the reference of a client that primes.
  bool prime(const Vec3& eye, const Vec3& aim);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// |T ∩ T_ref| / |T_ref| (1 when the reference is empty).
double triangle_accuracy(const SelectiveMesh& mesh, const SelectiveMesh& reference);

struct VdrWalkOptions {
  // Each frame lasts at least this (a client with a display paces its frames); 0: no pacing.
  double frame_ms = 0.0;
  // Draws the mesh from the frame's true view and returns T_r, ms; none: T_r = 0.
  std::function<double(const SelectiveMesh&, const VdrFrame&)> render;
  const VdrModel* reference = nullptr;  // for accuracy; none: not measured
  uint32_t accuracy_every = 5;          // the thesis sampled every 5 frames
  bool prime = false;                   // VdrClient::prime() on the first view (the reference too)
  // Called after start-up (or before frame 0) and after the last frame, before the reference
  // runs: many clients measured together meet there, so all walk at once and no reference takes
  // CPU from a walk.
  std::function<void()> after_start_up, before_reference;
};

struct VdrWalkFrame {
  VdrFrameReport report;
  double render_ms = 0.0, frame_ms = 0.0;
  double accuracy = -1.0;  // -1: not sampled this frame
};

struct VdrWalkResult {
  std::vector<VdrWalkFrame> frames;
  VdrClientStats stats;  // start-up's batches included
  VdrPrimeReport prime;  // empty when the walk did not prime
  double mean_frame_ms = 0, mean_update_ms = 0, mean_render_ms = 0, mean_triangles = 0, mean_ops = 0;
  double mean_accuracy = -1;     // over the sampled frames
  double unmodified_share = 0;   // of all frames
  double batch_p50_ms = 0, batch_p99_ms = 0;  // T_g's quantiles over the walk's batches
};

// The q-quantile of `v` (0 when empty).
double quantile(std::vector<double> v, double q);

// Walks `path` with `client` (built with `options`, whose settings the reference repeats).
VdrWalkResult walk_vdr(VdrClient& client, const VdrClientOptions& options, const std::vector<VdrFrame>& path,
                       const VdrWalkOptions& walk);

}  // namespace cellwalk::vdr
