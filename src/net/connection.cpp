// Framed, shaped TCP connections (docs/protocol.md, "Frames" and "Links").
#include "cellwalk/net/connection.hpp"

#include <algorithm>

#include "cellwalk/core/error.hpp"

namespace cellwalk::net {

namespace asio = boost::asio;
using asio::ip::tcp;

Clock::time_point LinkShaper::arrival(size_t bytes, Clock::time_point now) {
  const double transfer_s = shape_.bandwidth_mbit > 0 ? double(bytes) * 8.0 / (shape_.bandwidth_mbit * 1e6) : 0.0;
  busy_until_ = std::max(busy_until_, now) +
                std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(transfer_s));
  return busy_until_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::milli>(shape_.latency_ms));
}

Connection::Connection(tcp::socket socket, LinkShape outgoing, ConnectionLimits limits)
    : socket_(std::move(socket)),
      send_timer_(socket_.get_executor()),
      stall_timer_(socket_.get_executor()),
      shaper_(outgoing),
      limits_(limits) {
  boost::system::error_code ec;
  socket_.set_option(tcp::no_delay(true), ec);  // small requests go at once
}

void Connection::start(OnMessage on_message, OnClose on_close) {
  on_message_ = std::move(on_message);
  on_close_ = std::move(on_close);
  open_ = true;
  read_header();
}

void Connection::read_header() {
  asio::async_read(socket_, asio::buffer(header_), [self = shared_from_this()](boost::system::error_code ec, size_t n) {
    if (!self->open_) return;
    if (ec) return self->close(ec == asio::error::eof ? "the peer closed the connection" : "read failed: " + ec.message());
    self->bytes_received_ += n;
    FrameHeader h;
    try {
      h = parse_frame_header(self->header_, self->limits_.max_payload);
    } catch (const ProtocolError& e) {
      return self->close(e.what());
    }
    self->read_payload(h);
  });
}

void Connection::read_payload(FrameHeader header) {
  payload_.assign(header.length, 0);
  // A peer that sends a header and then stalls is dropped: the session holds a buffer for it.
  stall_timer_.expires_after(limits_.stall);
  stall_timer_.async_wait([self = shared_from_this()](boost::system::error_code ec) {
    if (!ec && self->open_) self->close("stalled in the middle of a message");
  });
  asio::async_read(socket_, asio::buffer(payload_), [self = shared_from_this(), header](boost::system::error_code ec, size_t n) {
    self->stall_timer_.cancel();
    if (!self->open_) return;
    if (ec) return self->close(ec == asio::error::eof ? "the peer closed the connection mid-message" : "read failed: " + ec.message());
    self->bytes_received_ += n;
    try {
      self->on_message_(header.type, std::move(self->payload_));
    } catch (const std::exception& e) {
      return self->close(e.what());
    }
    if (self->open_ && !self->closing_) self->read_header();
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
    asio::async_write(self->socket_, asio::buffer(self->queue_.front().frame),
                      [self](boost::system::error_code wec, size_t n) {
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
  boost::system::error_code ec;
  send_timer_.cancel();
  stall_timer_.cancel();
  socket_.shutdown(tcp::socket::shutdown_both, ec);
  socket_.close(ec);
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
