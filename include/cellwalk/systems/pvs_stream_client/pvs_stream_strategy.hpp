// The PVS streaming client as a strategy (seed 004, Zheng ch. 7, §7.2–7.4 over TCP; digest
// §3.10–3.11): the walker's world comes over a socket from a PVS server (`cellwalk serve`, or one
// the strategy starts on 127.0.0.1 over the same world, with the link shaped). The client keeps
// at most `entries` rows of visible sets and exactly the objects of their union; a network thread
// runs one transaction at a time (the rows of the prefetching area it lacks and only the objects
// it does not hold, ΔS = S_J − S_I, in one round trip), replacing rows as §7.4 says and naming
// the objects it deleted in its next fetch. Each frame draws the current cell's row, culled to
// the view frustum; when that row has not arrived the frame waits for it (a stall), at most
// wait_ms, then draws the last row it had (the objects it lacks are missed through late data).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

// Name: "pvs-stream[:key=value,...]" with keys
//   prefetch=pbnp        snp (the cell and its 8 neighbours, on each cell change), pbnp (h(R) of
//                        Table 7.1, on each region change), or speed (pbnp whose band is the
//                        distance the viewer covers in one transaction time, measured: the
//                        speed-aware prefetch the thesis leaves as future work, digest §7.2)
//   band=0.25            pbnp's region band, a fraction of the cell (speed: its smallest)
//   server=HOST:PORT     a running `cellwalk serve` of the same world; none: the strategy serves
//                        the world itself on 127.0.0.1 (a real socket), with the link below
//   server=http://H:P/W  no PVS server: the world file W on a plain web server (nginx), read by
//                        HTTP range requests; the client finds its rows and ΔS in it itself
//   latency_ms=0         that link's one-way delay, each direction (a range request: twice)
//   bandwidth_mbit=0     that link's rate, each direction (0: unlimited)
//   wait_ms=1000         the longest a frame waits for its cell's row
//   pace=1               follow the path's clock: a frame is not drawn before its path time
//                        (the viewer moves at the path's speed while data travel)
//   entries=9            rows the client keeps (§7.4's cache size)
//   level=0              the level of detail asked for
struct PvsStreamConfig {
  enum class Prefetch { kSnp, kPbnp, kSpeed };
  Prefetch prefetch = Prefetch::kPbnp;
  double band = 0.25;
  std::string url;   // the world on a web server (http://...); empty: a PVS server
  std::string host;  // empty (and no url): the strategy's own server
  uint16_t port = 0;
  double latency_ms = 0.0, bandwidth_mbit = 0.0;
  double wait_ms = 1000.0;
  bool pace = true;
  int entries = 9;
  uint32_t level = 0;
};
bool is_pvs_stream_strategy_name(const std::string& name);
PvsStreamConfig parse_pvs_stream_strategy_name(const std::string& name);

struct PvsStreamCounters {
  uint64_t frames = 0;
  uint64_t stall_frames = 0;   // frames that waited for their cell's row (start-up excluded)
  uint64_t late_frames = 0;    // frames drawn without their cell's row (it came after wait_ms)
  uint64_t cell_crossings = 0;
  uint64_t transactions = 0;   // fetches sent
  uint64_t cache_swaps = 0;    // rows replaced (§7.4)
  uint64_t rows_received = 0, objects_received = 0, objects_dropped = 0;
  uint64_t bytes_received = 0;  // every frame of every reply
  double startup_ms = 0.0;      // from the first frame to its cell's row and objects
  double transaction_ms_sum = 0.0, transaction_ms_max = 0.0;  // request sent to reply done
  double band_sum = 0.0;        // Σ over frames of the band used (speed: it varies)
};

class PvsStreamStrategy : public Strategy {
 public:
  // Connects (or starts its server and connects) and checks the server's world is this world.
  // Throws Error when the world has no visible sets over a 2D grid, the server cannot be reached
  // or serves another world.
  PvsStreamStrategy(const World& world, const PvsStreamConfig& config, const StrategyOptions& options);
  ~PvsStreamStrategy() override;
  std::string name() const override;
  // Throws Error when the network thread failed (the server closed, refused, or the budget
  // cannot hold the current cell's objects), with its reason.
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  uint64_t resident_bytes() const override;
  uint64_t peak_resident_bytes() const override;
  PvsStreamCounters counters() const;  // thread-safe
  // The counters above, named, for walk's report (thread-safe).
  std::vector<std::pair<std::string, double>> walk_counters() const override;
  // Each transaction's time, request sent to reply done, in order (thread-safe).
  std::vector<double> transaction_times_ms() const;
  // The id of the view cell `camera` stands in (its stored set is the row drawn there), if any.
  std::optional<uint32_t> cell_id(const Camera& camera) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
