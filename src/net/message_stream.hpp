// How a Connection's frames travel (docs/protocol.md, "Frames" and "WebSocket"): whole frames
// over a TCP byte stream, or one frame per binary WebSocket message (browsers). The Connection
// above it shapes, queues and bounds the same way whatever the stream.
#pragma once

// Boost 1.74's Asio uses std::exchange without including <utility>.
#include <utility>
#include <boost/asio.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/net/frame.hpp"

namespace cellwalk::net {

// REQUIRES: used only from its executor's thread; one read and one write in flight at most.
class MessageStream {
 public:
  // `closed` holds the reason when the stream ended or the frame broke the protocol; else the
  // frame's header and payload and the bytes it took on the wire.
  struct Read {
    std::optional<std::string> closed;
    FrameHeader header;
    std::vector<uint8_t> payload;
    size_t wire_bytes = 0;
  };
  using ReadHandler = std::function<void(Read)>;
  using WriteHandler = std::function<void(boost::system::error_code, size_t)>;

  virtual ~MessageStream() = default;
  virtual boost::asio::any_io_executor executor() = 0;
  // Reads one frame of at most `max_payload` bytes of payload; a peer that starts a frame and
  // then stalls for `stall` is dropped.
  virtual void read(uint32_t max_payload, std::chrono::milliseconds stall, ReadHandler handler) = 0;
  // REQUIRES: `frame` stays alive until the handler runs.
  virtual void write(std::span<const uint8_t> frame, WriteHandler handler) = 0;
  virtual void close() = 0;
};

std::unique_ptr<MessageStream> tcp_message_stream(boost::asio::ip::tcp::socket socket);

}  // namespace cellwalk::net
