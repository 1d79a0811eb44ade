// Framed connections for cellwalk's servers and clients (Boost.Asio), over TCP or a WebSocket,
// with the link shaped per direction: a one-way delay and a rate, so that loopback sockets carry
// real delays (docs/protocol.md, "Links"). Everything here runs on one single-threaded
// io_context: a server is one thread, however many sessions it holds.
#pragma once

// Boost 1.74's Asio uses std::exchange without including <utility>.
#include <utility>
#include <boost/asio.hpp>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cellwalk/net/frame.hpp"

namespace cellwalk::net {

using Clock = std::chrono::steady_clock;

// One direction of a link. Zero bandwidth: unlimited.
struct LinkShape {
  double latency_ms = 0.0;
  double bandwidth_mbit = 0.0;
};

// When messages sent through a shaped direction arrive: each waits for the ones before it to
// pass at the link's rate, then travels for the delay. Thread-safety: none.
class LinkShaper {
 public:
  explicit LinkShaper(LinkShape shape) : shape_(shape) {}
  Clock::time_point arrival(size_t bytes, Clock::time_point now);

 private:
  LinkShape shape_;
  Clock::time_point busy_until_{};
};

// What one session may hold: bounded, whatever the peer sends or fails to read.
struct ConnectionLimits {
  uint32_t max_payload = 1u << 20;                    // bytes of one incoming message
  size_t max_queued_bytes = size_t(64) << 20;         // outgoing bytes not yet written
  std::chrono::milliseconds stall{10000};             // to finish a message once its header came
};

class MessageStream;  // how the frames travel (src/net/message_stream.hpp)

// A framed connection. Owned through shared_ptr: its pending operations keep it alive.
// REQUIRES: used only from its io_context's thread.
class Connection : public std::enable_shared_from_this<Connection> {
 public:
  // A message handler may throw ProtocolError (or Error): the connection closes with its text.
  using OnMessage = std::function<void(uint8_t type, std::vector<uint8_t> payload)>;
  using OnClose = std::function<void(const std::string& reason)>;

  Connection(boost::asio::ip::tcp::socket socket, LinkShape outgoing, ConnectionLimits limits);
  // Any stream of frames (a WebSocket from WebListener).
  Connection(std::unique_ptr<MessageStream> stream, LinkShape outgoing, ConnectionLimits limits);
  ~Connection();
  void start(OnMessage on_message, OnClose on_close);
  // Queues one message; it is written when the shaped link delivers it. Closes the connection
  // when the peer lets more than max_queued_bytes pile up.
  void send(uint8_t type, std::span<const uint8_t> payload);
  // Closes after the messages already queued are written; on_close gets `reason`.
  void close_after_sending(const std::string& reason);
  void close(const std::string& reason);
  // The largest incoming message from now on (a protocol whose first message is its largest).
  void set_max_payload(uint32_t bytes) { limits_.max_payload = bytes; }
  bool open() const { return open_; }
  uint64_t bytes_sent() const { return bytes_sent_; }
  uint64_t bytes_received() const { return bytes_received_; }
  size_t queued_bytes() const { return queued_bytes_; }

 private:
  struct Outgoing {
    std::vector<uint8_t> frame;
    Clock::time_point due;
  };
  void read_next();
  void write_next();

  std::unique_ptr<MessageStream> stream_;
  boost::asio::steady_timer send_timer_;
  LinkShaper shaper_;
  ConnectionLimits limits_;
  OnMessage on_message_;
  OnClose on_close_;
  std::deque<Outgoing> queue_;
  bool writing_ = false, open_ = false, closing_ = false;
  std::string closing_reason_;
  size_t queued_bytes_ = 0;
  uint64_t bytes_sent_ = 0, bytes_received_ = 0;
};

// Accepts connections on 127.0.0.1 (or `address`), port 0 choosing a free one.
class Listener {
 public:
  Listener(boost::asio::io_context& io, uint16_t port, const std::string& address = "127.0.0.1");
  uint16_t port() const { return port_; }
  void accept(std::function<void(boost::asio::ip::tcp::socket)> on_socket);
  void close();

 private:
  void accept_next();
  boost::asio::ip::tcp::acceptor acceptor_;
  uint16_t port_ = 0;
  std::function<void(boost::asio::ip::tcp::socket)> on_socket_;
};

}  // namespace cellwalk::net
