// The VDR streaming server (seed 004, §4.1, Fig. 5.4, §8.2.1's many users): one model's
// progressive mesh and vsplit DAG, read-only and shared by every session; per session, the cut
// (status bit and counter per node, the fronts) and a traversal. Each view request is answered
// by one batch of at most 64 KB: MANAGE-TRAVERSAL's ecols, then its vsplits. One thread, async
// (no thread per client); a session that breaks the protocol, stalls mid-message, falls out of
// lockstep, lets its batches pile up or falls silent is dropped alone, with a reason
// (docs/protocol.md); a session past max_sessions is refused.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "cellwalk/net/connection.hpp"
#include "cellwalk/systems/vdr/vdr_file.hpp"
#include "cellwalk/systems/vdr/vdr_protocol.hpp"

namespace cellwalk::vdr {

struct VdrServerOptions {
  uint16_t port = 0;    // 0: a free port
  std::string address = "127.0.0.1";
  net::LinkShape link;  // the server → client direction (the thesis held packets on the server)
  // A view request is 55 bytes and a hello 8: nothing larger is read.
  net::ConnectionLimits limits{256, size_t(16) << 20, std::chrono::milliseconds(10000)};
  // Sessions at once: one more is told the server is full and closed. With each session's
  // memory bounded (its cut is a few bytes a node), this bounds the server's.
  uint32_t max_sessions = 256;
  // A session that sends nothing for this long is dropped (a client draws, so requests, every
  // frame); 0: never.
  std::chrono::milliseconds idle{std::chrono::minutes(10)};
  std::function<void(const std::string&)> log;  // one line per session event; none: silent
};

struct VdrServerStats {
  uint64_t sessions_opened = 0, sessions_dropped = 0, sessions_refused = 0, batches = 0, ops = 0, bytes_sent = 0;
  uint64_t sessions_open = 0;  // now
  double traversal_ms = 0.0;  // MANAGE-TRAVERSAL and encoding, summed over every batch
  double cpu_ms = 0.0;        // the serving thread's CPU time, once run() has returned
  // What the sessions held at the most, together and the largest one: cut, fronts, shadow mesh
  // and batches not yet written (the model is shared and counted apart).
  uint64_t peak_session_bytes = 0, peak_one_session_bytes = 0;
  uint64_t model_bytes = 0;
};

// The welcome every session gets: the model's size, bounds and base mesh.
VdrWelcome welcome_of(const VdrModel& model);

class VdrServer {
 public:
  // REQUIRES: `model` outlives the server. Throws Error when it cannot listen.
  VdrServer(const VdrModel& model, VdrServerOptions options);
  ~VdrServer();
  uint16_t port() const;
  // Serves on the calling thread until stop().
  void run();
  void stop();                   // thread-safe
  VdrServerStats stats() const;  // thread-safe

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk::vdr
