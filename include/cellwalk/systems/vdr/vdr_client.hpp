// The VDR streaming client (seed 004, §4.5, Figs. 5.5 and 6.2; digest §3.7–§3.9): the selective
// mesh, the batch applier and the two procedures — RENDER, the caller's thread, which applies at
// most one batch a frame and never waits for the network, and GET-UPDATES, a thread of its own
// that sends view requests and receives batches (pipelined: up to f requests in flight).
//   one frame ahead (LAN, f = 1): the request sent at frame i is for frame i + 1, its view
//     predicted by first-order dead reckoning E' = E_c + (E_c − E_p), A' likewise (§5.3);
//   f frames ahead (WAN): E' = E_c + k (E_c − E_p) for the request that will be applied k
//     frames later; f = ⌈T_g / (T_u + T_r)⌉ (Eq. 6.3.1) from smoothed timings when adaptive;
//   a late batch leaves the frame unmodified, and an unmodified frame sends nothing, so never
//     more than f batches are pending (§5.3, Fig. 6.4);
//   the budget B: by default the server holds it (each request carries B, and the server's cut
//     is the mesh the client will have: docs/vdr.md "The budget"); with server_budget off, the
//     thesis's alarm level L = B − 2 N f: above it the request asks for BUDGET mode, so the mesh
//     stays under B triangles with f FREE batches in flight (§6.3).
// A sequential client (Table 5.1's "Seq") sends the true view and waits for its batch.
//
// Thread-safety: frame(), rendered() and mesh() from one thread (RENDER); stats() from any.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cellwalk/net/connection.hpp"
#include "cellwalk/systems/vdr/selective_mesh.hpp"
#include "cellwalk/systems/vdr/vdr_protocol.hpp"

namespace cellwalk::vdr {

enum class Predictor : uint8_t { kNone = 0, kLinear = 1, kTurn = 2 };
std::string predictor_name(Predictor p);  // "none", "linear", "turn"
Predictor parse_predictor(const std::string& word);

// Where a point moving through p2, p1, p0 (oldest first, one frame apart) will be k frames after
// p0 under `predictor`. Turn takes a step 8 times the one before and longer than `least_jump`
// for a jump (docs/vdr.md "Prediction").
Vec3 predict_point(Predictor predictor, const Vec3& p2, const Vec3& p1, const Vec3& p0, uint32_t k, float least_jump = 0.0f);

// Start-up's requests in flight at once (VdrClient::prime), and the most catch-up requests
// catch_up_as_start_up makes (far under the 256 batches a lockstep server holds unconfirmed).
inline constexpr uint32_t kPrimeWindow = 16;
inline constexpr uint32_t kMaxJumpCatchUp = 64;

struct VdrClientOptions {
  net::LinkShape outgoing;  // the client → server direction
  Hello hello;              // traversal, error units, lockstep
  uint32_t budget = 60000;  // B, triangles
  bool server_budget = true;  // false: the thesis's alarm level
  uint32_t n = 500;         // N, ops per direction per frame
  float tau = 0.001f;       // τ, a fraction of the viewport
  float alpha = 0.6f;       // the view cone's half-angle, radians
  uint32_t span = 1;        // f; the starting value when adaptive
  bool adaptive_span = false;
  // Beyond the thesis: fill the pipeline one request a frame, each predicted for the frame it
  // will arrive by (k ≥ f), instead of f requests at the first frame for frames 1…f that all
  // arrive f frames late (docs/vdr.md "The span").
  bool gradual_fill = false;
  // Beyond the thesis: the frame after a jump of the eye or the aim (a step 8 times the one
  // before), this many extra requests for the view the regular request predicts, applied
  // together with its batch (docs/vdr.md "Jumps"). Those past convergence come back empty.
  uint32_t jump_catch_up = 0;
  // With jump_catch_up: after prime(), at least as many as start-up's batches, up to
  // kMaxJumpCatchUp (a view's cut from far away costs about what the first view's did; a large
  // model needs more).
  bool catch_up_as_start_up = false;
  uint32_t max_span = 16;
  bool sequential = false;
  // How a request's view is predicted k frames ahead: none (the current view: an ablation),
  // linear (§5.3's dead reckoning, the thesis's) or turn (beyond the thesis: each of E and A keeps
  // its last speed and turns on by its last turn, a coordinated turn; docs/vdr.md "Prediction").
  Predictor predictor = Predictor::kLinear;
  double timeout_s = 30.0;  // for the welcome, and for each batch of a sequential client
  // prime(): the most batches it takes for the first view (beyond the thesis; docs/vdr.md
  // "Start-up").
  uint32_t prime_batches = 4096;
};

struct VdrPrimeReport {
  uint32_t batches = 0;    // applied, the last empty one included when it converged
  bool converged = false;  // a batch came back empty: the cut is the first view's
  uint32_t triangles = 0;
  double ms = 0.0;         // the start-up time, wall clock
};

struct VdrFrameReport {
  bool modified = false;  // a batch was applied this frame
  uint32_t ops = 0, triangles = 0, span = 0, pending = 0;
  BudgetMode mode = BudgetMode::kFree;  // of the requests sent this frame
  double update_ms = 0.0;  // T_u: applying the batch
  double wait_ms = 0.0;    // a sequential client's wait for its batch
};

struct VdrClientStats {
  uint64_t batches = 0, ops = 0, bytes_received = 0, bytes_sent = 0, frames = 0, unmodified = 0;
  uint64_t requests = 0, catch_up_requests = 0;  // views sent, start-up's included; of them, catch-up
  std::vector<double> batch_ms;  // T_g per batch: request handed to the link → batch received
  uint32_t largest_span = 0;
};

class VdrClient {
 public:
  // Connects to a VDR server and takes the base mesh. Throws Error when it cannot.
  VdrClient(const std::string& host, uint16_t port, VdrClientOptions options);
  ~VdrClient();
  VdrClient(const VdrClient&) = delete;
  VdrClient& operator=(const VdrClient&) = delete;

  // Start-up (beyond the thesis): refines the mesh for the first view before frame 0 — a
  // viewer's loading screen — with a window of requests for that one view in flight, until a
  // batch comes back empty or options.prime_batches were applied. REQUIRES: before frame().
  VdrPrimeReport prime(const Vec3& eye, const Vec3& aim);
  // One frame of RENDER, before drawing: `eye` and `aim` are the frame's true view. Throws Error
  // when the server dropped the session or a batch does not apply (naming why).
  VdrFrameReport frame(const Vec3& eye, const Vec3& aim);
  // The view cone's half-angle for the requests from now on (a viewer's lens; each request
  // carries it).
  void set_alpha(float alpha);
  // T_r of the frame just drawn (0 if the caller does not draw), for Eq. 6.3.1.
  void rendered(double ms);

  const SelectiveMesh& mesh() const;
  const VdrWelcome& welcome() const;
  uint32_t span() const;
  VdrClientStats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk::vdr
