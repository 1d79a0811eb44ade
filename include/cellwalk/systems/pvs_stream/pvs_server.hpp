// The PVS streaming server and a blocking client (seed 004, §7.3–7.4 made real over TCP;
// docs/protocol.md, "PVS streaming"). The server holds one world with visible sets over a 2D
// grid of view cells (over TCP, and over WebSockets to browsers) and answers, per session, fetches of rows and of the geometry the client
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
#include "cellwalk/visibility/stored_pvs.hpp"

namespace cellwalk::pvs_stream {

struct PvsServerOptions {
  uint16_t port = 0;        // 0: a free port
  net::LinkShape link;      // the server → client direction
  net::ConnectionLimits limits{1u << 20, size_t(256) << 20, std::chrono::milliseconds(10000)};
  std::function<void(const std::string&)> log;  // one line per session event; none: silent
  // The browser client (docs/web.md): one more port, HTTP, serving the folder `web_root` and
  // the same protocol over WebSockets on /ws. Its sessions get levels without zstd.
  bool web = false;
  uint16_t web_port = 0;  // 0: a free port
  std::string web_root;   // empty: /ws only
};

struct PvsServerStats {
  uint64_t sessions_opened = 0, sessions_dropped = 0, fetches = 0, objects_sent = 0, bytes_sent = 0;
  // What the sessions held at the most: each one's mirror of its client's objects and its
  // replies not yet written (the world and its sets are shared and counted apart).
  uint64_t peak_session_bytes = 0;
  uint64_t web_sessions = 0;
  uint64_t web_files_served = 0, web_requests_refused = 0;  // set when run() returns
};

// The grid a world's stored sets lie on, as a Welcome (without world_bytes). Throws Error when
// the world has no sets or they are not over a 2D grid.
Welcome grid_of(const World& world);
// Every object's colour and box, for the catalog message.
Catalog catalog_of(const World& world);

class PvsServer {
 public:
  // REQUIRES: `world` outlives the server.
  PvsServer(const World& world, PvsServerOptions options);
  ~PvsServer();
  uint16_t port() const;
  uint16_t web_port() const;  // REQUIRES: options.web
  // Serves on the calling thread until stop().
  void run();
  // Thread-safe.
  void stop();
  PvsServerStats stats() const;  // thread-safe

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// §7.3's answer to one fetch: the rows asked for and the objects of their union that `held`
// (the mirror of what the client holds, one byte per object) lacks, in id order; marks those
// held. The client's drops are applied first. Throws net::ProtocolError naming a cell without
// a visible set.
struct PlannedReply {
  RowsReply rows;
  std::vector<uint32_t> send;
};
PlannedReply plan_reply(const visibility::StoredPvs& pvs, std::vector<uint8_t>& held, const FetchRequest& request);

// The whole answer to one fetch, as a client sees it.
struct PvsReply {
  RowsReply rows;
  std::vector<ObjectReply> objects;
  uint64_t bytes = 0;  // what crossed the network for it
};

// Where a streaming client's rows and objects come from: a PVS server over its protocol
// (PvsClient) or a world file read directly (PvsFileSource; a remote one by HTTP range requests
// from a plain web server). Thread-safety: none, except cancel().
class PvsSource {
 public:
  virtual ~PvsSource() = default;
  virtual const Welcome& welcome() const = 0;
  // One fetch and its whole reply. Throws Error when the source fails or refuses.
  virtual PvsReply fetch(const FetchRequest& request) = 0;
  // Makes a fetch in flight (or the next) end soon with an Error; callable from any thread.
  virtual void cancel() {}
};

// A client that waits for each reply (tests, tools). Its own direction is shaped too: a fetch
// leaves after `outgoing`'s delay. Thread-safety: none.
class PvsClient final : public PvsSource {
 public:
  // Connects and exchanges hello/welcome. Throws Error when it cannot.
  PvsClient(const std::string& host, uint16_t port, net::LinkShape outgoing = {});
  ~PvsClient() override;
  const Welcome& welcome() const override;
  using Reply = PvsReply;
  // Throws Error if the server answers with an error or closes.
  PvsReply fetch(const FetchRequest& request) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// No server: the client answers its own fetches from a world file, keeping the mirror a server
// would keep, so it reads exactly the rows and the objects a server would send (§7.3's ΔS).
// With the world opened from a URL this is the walkthrough served by a plain web server (issue
// 20): every row and object is one or more HTTP range requests, the objects' six at a time (as a
// browser's connections to one host). `bytes` of a reply count the pages read for it. REQUIRES: `world` outlives the source.
class PvsFileSource final : public PvsSource {
 public:
  explicit PvsFileSource(const World& world);
  ~PvsFileSource() override;
  const Welcome& welcome() const override;
  PvsReply fetch(const FetchRequest& request) override;
  void cancel() override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk::pvs_stream
