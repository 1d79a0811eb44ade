// The VDR streaming client as a strategy (seed 004, Zheng ch. 4–6; docs/vdr.md "The vdr
// strategy"): the walker's model comes over a socket as vsplits and ecols from a VDR server
// (`cellwalk serve MODEL.cwvdr`, or one the strategy starts on 127.0.0.1 over the model, with
// the link shaped), and each frame draws the client's selective mesh as it stands — whatever
// the network has delivered — so `walk` and `compare` measure it like any other strategy.
// The world is the same model imported (`cellwalk import`): it gives compare its ground truth
// and the walk its paths; the strategy checks that the two have the same bounds.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cellwalk/strategy/strategy.hpp"
#include "cellwalk/systems/vdr/vdr_client.hpp"

namespace cellwalk {

// Name: "vdr[:key=value,...]" with keys
//   model=FILE.cwvdr     the model (`cellwalk vdr-build`); default: the world's file name with
//                        .cwvdr for .cww
//   server=HOST:PORT     a running `cellwalk serve FILE.cwvdr`; none: the strategy serves the
//                        model itself on 127.0.0.1 (a real socket), with the link below
//   latency_ms=0         one-way delay, each direction (the own server's and the client's)
//   traversal=priority   priority, linear or constant (§4.3)
//   budget=60000         B, triangles
//   ops=500              N, ops per direction per frame
//   tau=0.001            τ, a fraction of the viewport
//   span=auto            f: a number of frames, or auto (Eq. 6.3.1)
//   predictor=turn       none, linear (the thesis's) or turn
//   client=ours          ours (server-held budget, start-up, gradual fill, catch-up after
//                        jumps) or thesis (the alarm level and none of those)
//   pace=1               follow the path's clock: a frame is not drawn before its path time
struct VdrStrategyConfig {
  std::string model;  // empty: from the world's file name
  std::string host;   // empty: the strategy's own server
  uint16_t port = 0;
  double latency_ms = 0.0;
  vdr::VdrClientOptions client;
  bool ours = true;
  bool pace = true;
};

bool is_vdr_strategy_name(const std::string& name);
VdrStrategyConfig parse_vdr_strategy_name(const std::string& name);

class VdrStrategy : public Strategy {
 public:
  // Reads the model, starts its server or connects to `host`, and primes the client (ours) at
  // the first frame. Throws Error when the model is missing or not this world's, the server
  // cannot be reached or serves another model, or a memory budget is given (the client's mesh is
  // bounded by budget=B triangles instead).
  VdrStrategy(const World& world, const VdrStrategyConfig& config, const StrategyOptions& options);
  ~VdrStrategy() override;
  std::string name() const override;
  // Throws Error when the session failed (the server dropped it, a batch did not apply).
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  // The client's mesh and id maps, and with its own server the shared model and the session.
  uint64_t resident_bytes() const override;
  uint64_t peak_resident_bytes() const override;
  // Batches, ops, bytes, unmodified frames, the largest span, T_g's p50, start-up time.
  std::vector<std::pair<std::string, double>> walk_counters() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
