// The PVS streaming server and a blocking client (seed 004, §7.3–7.4 made real over TCP;
// docs/protocol.md, "PVS streaming"). The server holds one world with visible sets over a 2D
// grid of view cells and answers, per session, fetches of rows and of the geometry the client
// lacks: it mirrors which objects each client holds (the client names what it dropped), so a
// fetch is one round trip and sends ΔS = S_J − S_I only. One thread, many sessions; a session
// that breaks the protocol, stalls or lets its replies pile up is dropped alone, with a reason.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cellwalk/net/connection.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/pvs_stream/pvs_protocol.hpp"

namespace cellwalk::pvs_stream {

struct PvsServerOptions {
  uint16_t port = 0;        // 0: a free port
  net::LinkShape link;      // the server → client direction
  net::ConnectionLimits limits{1u << 20, size_t(256) << 20, std::chrono::milliseconds(10000)};
  std::function<void(const std::string&)> log;  // one line per session event; none: silent
};

struct PvsServerStats {
  uint64_t sessions_opened = 0, sessions_dropped = 0, fetches = 0, objects_sent = 0, bytes_sent = 0;
  // What the sessions held at the most: each one's mirror of its client's objects and its
  // replies not yet written (the world and its sets are shared and counted apart).
  uint64_t peak_session_bytes = 0;
};

// The grid a world's stored sets lie on, as a Welcome (without world_bytes). Throws Error when
// the world has no sets or they are not over a 2D grid.
Welcome grid_of(const World& world);

class PvsServer {
 public:
  // REQUIRES: `world` outlives the server.
  PvsServer(const World& world, PvsServerOptions options);
  ~PvsServer();
  uint16_t port() const;
  // Serves on the calling thread until stop().
  void run();
  // Thread-safe.
  void stop();
  PvsServerStats stats() const;  // thread-safe

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A client that waits for each reply (tests, tools). Its own direction is shaped too: a fetch
// leaves after `outgoing`'s delay. Thread-safety: none.
class PvsClient {
 public:
  // Connects and exchanges hello/welcome. Throws Error when it cannot.
  PvsClient(const std::string& host, uint16_t port, net::LinkShape outgoing = {});
  ~PvsClient();
  const Welcome& welcome() const;
  struct Reply {
    RowsReply rows;
    std::vector<ObjectReply> objects;
    uint64_t bytes = 0;  // every frame of the reply
  };
  // One fetch and its whole reply. Throws Error if the server answers with an error or closes.
  Reply fetch(const FetchRequest& request);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk::pvs_stream
