// The web side of cellwalk's servers (docs/protocol.md, "WebSocket"; docs/web.md): one HTTP
// port that serves a folder of static files (the browser client) and upgrades requests for
// /ws to WebSockets, each binary message carrying one frame of the same protocol the TCP
// clients speak. Boost.Beast, on the server's one io_context.
#pragma once

#include <utility>
#include <boost/asio.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "cellwalk/net/connection.hpp"

namespace cellwalk::net {

struct WebListenerOptions {
  uint16_t port = 0;                 // 0: a free one
  std::string address = "127.0.0.1";
  std::string root;                  // the folder served; empty: only /ws is answered
  LinkShape link;                    // the server → browser direction of every WebSocket
  ConnectionLimits limits;
  size_t max_file_bytes = size_t(64) << 20;  // a larger file is answered 413
  std::function<void(const std::string&)> log;  // one line per refused request; none: silent
};

// What it served, for a server's statistics. Thread-safety: none (the io_context's thread).
struct WebListenerStats {
  uint64_t requests = 0, files_served = 0, refused = 0, websockets = 0, file_bytes = 0;
};

// Serves until close(). A connection that takes more than 10 s to send a request (from the end of
// the one before), or to take an answer, is closed; a path that leaves the root, a method other
// than GET and HEAD, a malformed request, or a WebSocket opened by another site's page (its
// Origin is not this server) gets a 4xx answer and nothing from the disk. REQUIRES: used only
// from `io`'s thread.
class WebListener {
 public:
  using OnWebSocket = std::function<void(std::shared_ptr<Connection>)>;
  // Throws Error when it cannot listen, or `root` is given and is no folder.
  WebListener(boost::asio::io_context& io, WebListenerOptions options);
  ~WebListener();
  uint16_t port() const;
  // Starts accepting; each WebSocket opened on /ws becomes a Connection (not yet started).
  // After close() (or the listener's end) none is handed on.
  void accept(OnWebSocket on_websocket);
  void close();
  const WebListenerStats& stats() const;

  struct Impl;  // opaque; shared with the HTTP sessions it serves (src/net/web_listener.cpp)

 private:
  std::shared_ptr<Impl> impl_;
};

// The file under `root` that a request target names, or "" when it names none safely: the query
// is dropped, %XX decoded, "/" is index.html; ".." segments, NULs, backslashes and anything
// resolving outside `root` (through a link too) give "". Exposed for tests.
std::string web_file_for(const std::string& root, const std::string& target);

}  // namespace cellwalk::net
