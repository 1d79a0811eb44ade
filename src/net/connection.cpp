// Framed, shaped connections over TCP (docs/protocol.md, "Frames" and "Links").
#include "cellwalk/net/connection.hpp"

#include <algorithm>

#include "cellwalk/core/error.hpp"
#include "net/message_stream.hpp"

namespace cellwalk::net {

namespace asio = boost::asio;
using asio::ip::tcp;

Clock::time_point LinkShaper::arrival(size_t bytes, Clock::time_point now) {
  const double transfer_s = shape_.bandwidth_mbit > 0 ? double(bytes) * 8.0 / (shape_.bandwidth_mbit * 1e6) : 0.0;
  busy_until_ = std::max(busy_until_, now) +
                std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(transfer_s));
  return busy_until_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::milli>(shape_.latency_ms));
}

// ---- Frames over a TCP byte stream ---------------------------------------------------------

namespace {

class TcpMessageStream final : public MessageStream {
 public:
  explicit TcpMessageStream(tcp::socket socket) : socket_(std::move(socket)), stall_timer_(socket_.get_executor()) {
    boost::system::error_code ec;
    socket_.set_option(tcp::no_delay(true), ec);  // small requests go at once
  }
  ~TcpMessageStream() override { *alive_ = false; }
  asio::any_io_executor executor() override { return socket_.get_executor(); }

  void read(uint32_t max_payload, std::chrono::milliseconds stall, ReadHandler handler) override {
    asio::async_read(socket_, asio::buffer(header_), [this, max_payload, stall, handler = std::move(handler)](
                                                         boost::system::error_code ec, size_t) mutable {
      if (ec) return handler({ec == asio::error::eof ? "the peer closed the connection" : "read failed: " + ec.message()});
      FrameHeader h;
      try {
        h = parse_frame_header(header_, max_payload);
      } catch (const ProtocolError& e) {
        return handler({e.what()});
      }
      read_payload(h, stall, std::move(handler));
    });
  }

  void write(std::span<const uint8_t> frame, WriteHandler handler) override {
    asio::async_write(socket_, asio::buffer(frame.data(), frame.size()), std::move(handler));
  }

  void close() override {
    boost::system::error_code ec;
    stall_timer_.cancel();
    socket_.shutdown(tcp::socket::shutdown_both, ec);
    socket_.close(ec);
  }

 private:
  void read_payload(FrameHeader header, std::chrono::milliseconds stall, ReadHandler handler) {
    payload_.assign(header.length, 0);
    // A peer that sends a header and then stalls is dropped: the session holds a buffer for it.
    // The timer's handler may run after the read it guards has ended (it fired as the read
    // finished) or after the stream is gone: it acts only for its own read of a live stream.
    stalled_ = false;
    const uint64_t read = ++reads_;
    stall_timer_.expires_after(stall);
    stall_timer_.async_wait([this, alive = alive_, read](boost::system::error_code ec) {
      if (ec || !*alive || read != reads_ || !reading_payload_) return;
      stalled_ = true;
      boost::system::error_code ignored;
      socket_.cancel(ignored);
    });
    reading_payload_ = true;
    asio::async_read(socket_, asio::buffer(payload_), [this, header, handler = std::move(handler)](
                                                          boost::system::error_code ec, size_t) {
      reading_payload_ = false;
      stall_timer_.cancel();
      if (stalled_) return handler({"stalled in the middle of a message"});
      if (ec)
        return handler({ec == asio::error::eof ? "the peer closed the connection mid-message" : "read failed: " + ec.message()});
      handler({std::nullopt, header, std::move(payload_), kFrameHeaderBytes + header.length});
    });
  }

  tcp::socket socket_;
  asio::steady_timer stall_timer_;
  std::array<uint8_t, kFrameHeaderBytes> header_{};
  std::vector<uint8_t> payload_;
  bool stalled_ = false, reading_payload_ = false;
  uint64_t reads_ = 0;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace

std::unique_ptr<MessageStream> tcp_message_stream(tcp::socket socket) {
  return std::make_unique<TcpMessageStream>(std::move(socket));
}

// ---- The connection ----------------------------------------------------------------------

Connection::Connection(tcp::socket socket, LinkShape outgoing, ConnectionLimits limits)
    : Connection(tcp_message_stream(std::move(socket)), outgoing, limits) {}

Connection::Connection(std::unique_ptr<MessageStream> stream, LinkShape outgoing, ConnectionLimits limits)
    : stream_(std::move(stream)), send_timer_(stream_->executor()), shaper_(outgoing), limits_(limits) {}

Connection::~Connection() = default;

void Connection::start(OnMessage on_message, OnClose on_close) {
  on_message_ = std::move(on_message);
  on_close_ = std::move(on_close);
  open_ = true;
  read_next();
}

void Connection::read_next() {
  stream_->read(limits_.max_payload, limits_.stall, [self = shared_from_this()](MessageStream::Read r) {
    if (!self->open_) return;
    if (r.closed) return self->close(*r.closed);
    self->bytes_received_ += r.wire_bytes;
    try {
      self->on_message_(r.header.type, std::move(r.payload));
    } catch (const std::exception& e) {
      return self->close(e.what());
    }
    if (self->open_ && !self->closing_) self->read_next();
  });
}

void Connection::send(uint8_t type, std::span<const uint8_t> payload) {
  if (!open_ || closing_) return;
  std::vector<uint8_t> frame = make_frame(type, payload);
  queued_bytes_ += frame.size();
  if (queued_bytes_ > limits_.max_queued_bytes) return close("the peer does not read what it asked for");
  const Clock::time_point due = shaper_.arrival(frame.size(), Clock::now());
  queue_.push_back({std::move(frame), due});
  if (!writing_) write_next();
}

void Connection::write_next() {
  if (queue_.empty() || !open_) {
    writing_ = false;
    if (closing_ && queue_.empty()) close(closing_reason_);
    return;
  }
  writing_ = true;
  send_timer_.expires_at(queue_.front().due);
  send_timer_.async_wait([self = shared_from_this()](boost::system::error_code ec) {
    if (ec || !self->open_) return;
    self->stream_->write(self->queue_.front().frame, [self](boost::system::error_code wec, size_t n) {
      if (!self->open_) return;
      if (wec) return self->close("write failed: " + wec.message());
      self->bytes_sent_ += n;
      self->queued_bytes_ -= self->queue_.front().frame.size();
      self->queue_.pop_front();
      self->write_next();
    });
  });
}

void Connection::close_after_sending(const std::string& reason) {
  if (!open_) return;
  closing_ = true;
  closing_reason_ = reason;
  if (!writing_) write_next();
}

void Connection::close(const std::string& reason) {
  if (!open_) return;
  open_ = false;
  send_timer_.cancel();
  stream_->close();
  queue_.clear();
  queued_bytes_ = 0;
  if (on_close_) on_close_(reason);
}

Listener::Listener(asio::io_context& io, uint16_t port, const std::string& address) : acceptor_(io) {
  boost::system::error_code ec;
  const tcp::endpoint endpoint(asio::ip::make_address(address, ec), port);
  if (ec) throw Error("listen: " + address + " is no IP address");
  acceptor_.open(endpoint.protocol(), ec);
  if (!ec) acceptor_.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) acceptor_.bind(endpoint, ec);
  if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) throw Error("listen on " + address + ":" + std::to_string(port) + ": " + ec.message() + "; choose another --port");
  port_ = acceptor_.local_endpoint().port();
}

void Listener::accept(std::function<void(tcp::socket)> on_socket) {
  on_socket_ = std::move(on_socket);
  accept_next();
}

void Listener::accept_next() {
  acceptor_.async_accept([this](boost::system::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor_.is_open()) return;
    if (!ec) on_socket_(std::move(socket));
    accept_next();
  });
}

void Listener::close() {
  boost::system::error_code ec;
  acceptor_.close(ec);
}

}  // namespace cellwalk::net
