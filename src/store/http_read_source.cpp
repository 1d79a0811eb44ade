// A world file read by HTTP/1.1 range requests (issue 20; RFC 9110 §14 range requests).
#include "cellwalk/store/http_read_source.hpp"

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <charconv>
#include <cstring>

#include "cellwalk/core/error.hpp"

namespace cellwalk {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;

namespace {

std::optional<uint64_t> parse_u64(std::string_view text) {
  uint64_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || text.empty()) return std::nullopt;
  return value;
}

// Runs the connection's own context until the one operation started on it has completed (or
// its stream's timer has cancelled it).
void run(asio::io_context& io) {
  io.restart();
  io.run();
}

std::string field(const http::response<http::vector_body<uint8_t>>& res, http::field f) {
  const auto v = res[f];
  return std::string(v.data(), v.size());
}

std::string range_text(uint64_t first, uint64_t last) {
  return "bytes " + std::to_string(first) + "-" + std::to_string(last);
}

}  // namespace

bool is_http_url(std::string_view path) { return path.starts_with("http://") || path.starts_with("https://"); }

HttpUrl parse_http_url(std::string_view url) {
  const std::string where(url);
  if (url.starts_with("https://")) fail(where, "https is not supported (cellwalk has no TLS); serve the world over http on a trusted network");
  if (!url.starts_with("http://")) fail(where, "is not an http:// URL");
  std::string_view rest = url.substr(7);
  const size_t slash = rest.find('/');
  const std::string_view authority = rest.substr(0, slash);
  HttpUrl out;
  out.target = slash == std::string_view::npos ? "/" : std::string(rest.substr(slash));
  const size_t colon = authority.rfind(':');
  out.host = std::string(authority.substr(0, colon));
  if (out.host.empty() || out.host.find_first_of("[]@ ") != std::string::npos)
    fail(where, "names no host, or one cellwalk cannot read (write http://HOST[:PORT]/PATH with a name or an IPv4 address)");
  if (colon != std::string_view::npos) {
    const auto port = parse_u64(authority.substr(colon + 1));
    if (!port || *port == 0 || *port > 65535) fail(where, "has a bad port (write a number in 1..65535 after the colon)");
    out.port = uint16_t(*port);
  }
  if (out.target.find_first_of(" \r\n") != std::string::npos) fail(where, "has spaces or line breaks in its path");
  return out;
}

std::optional<ContentRange> parse_content_range(std::string_view value) {
  if (!value.starts_with("bytes ")) return std::nullopt;
  value.remove_prefix(6);
  const size_t dash = value.find('-'), slash = value.find('/');
  if (dash == std::string_view::npos || slash == std::string_view::npos || slash < dash) return std::nullopt;
  const auto first = parse_u64(value.substr(0, dash));
  const auto last = parse_u64(value.substr(dash + 1, slash - dash - 1));
  const auto total = parse_u64(value.substr(slash + 1));
  if (!first || !last || !total || *first > *last || *last >= *total) return std::nullopt;
  return ContentRange{*first, *last, *total};
}

struct HttpReadSource::Connection {
  asio::io_context io;
  beast::tcp_stream stream{io};
  beast::flat_buffer buffer;
  bool used = false;  // has answered a request: the server may have closed it since
  bool keep = true;   // the server lets it stay open
};

HttpReadSource::HttpReadSource(const std::string& url, uint32_t timeout_ms)
    : url_(url), where_(parse_http_url(url)), timeout_ms_(timeout_ms) {
  auto c = take_connection();
  uint8_t first = 0;
  if (!request(*c, 0, 0, &first, true)) fail(url_, "the server closed the connection without answering");
  if (c->keep) give_back(std::move(c));
}

HttpReadSource::~HttpReadSource() = default;

std::unique_ptr<HttpReadSource::Connection> HttpReadSource::take_connection() {
  {
    const std::lock_guard lock(mutex_);
    if (!idle_.empty()) {
      auto c = std::move(idle_.back());
      idle_.pop_back();
      return c;
    }
  }
  auto c = std::make_unique<Connection>();
  beast::error_code ec;
  tcp::resolver resolver(c->io);
  const auto endpoints = resolver.resolve(where_.host, std::to_string(where_.port), ec);
  if (ec) fail(url_, "cannot resolve " + where_.host + ": " + ec.message());
  c->stream.expires_after(std::chrono::milliseconds(timeout_ms_));
  c->stream.async_connect(endpoints, [&](beast::error_code e, const tcp::endpoint&) { ec = e; });
  run(c->io);
  if (ec)
    fail(url_, "cannot connect to " + where_.host + ":" + std::to_string(where_.port) + " (" + ec.message() +
                   "); is the web server running?");
  connections_.fetch_add(1, std::memory_order_relaxed);
  return c;
}

void HttpReadSource::give_back(std::unique_ptr<Connection> c) {
  const std::lock_guard lock(mutex_);
  idle_.push_back(std::move(c));
}

bool HttpReadSource::request(Connection& c, uint64_t first, uint64_t last, void* dst, bool learn) {
  const std::string range = range_text(first, last);
  http::request<http::empty_body> req{http::verb::get, where_.target, 11};
  req.set(http::field::host, where_.host + ":" + std::to_string(where_.port));
  req.set(http::field::range, "bytes=" + std::to_string(first) + "-" + std::to_string(last));
  req.set(http::field::user_agent, "cellwalk");
  beast::error_code ec;
  c.stream.expires_after(std::chrono::milliseconds(timeout_ms_));
  http::async_write(c.stream, req, [&](beast::error_code e, size_t) { ec = e; });
  run(c.io);
  const uint64_t wanted = last - first + 1;
  http::response_parser<http::vector_body<uint8_t>> parser;
  parser.body_limit(std::max<uint64_t>(wanted, uint64_t(1) << 16));  // room for an error page
  if (!ec) {
    c.stream.expires_after(std::chrono::milliseconds(timeout_ms_));
    http::async_read(c.stream, c.buffer, parser, [&](beast::error_code e, size_t) { ec = e; });
    run(c.io);
  }
  const bool closed = ec == http::error::end_of_stream || ec == asio::error::eof ||
                      ec == asio::error::connection_reset || ec == asio::error::broken_pipe;
  if (closed && c.used && !parser.got_some()) return false;
  if (ec)
    fail(url_, range + ": " + (ec == beast::error::timeout ? "no answer within " + std::to_string(timeout_ms_) + " ms" : ec.message()) +
                   "; is the web server running and reachable?");
  c.used = true;
  const auto& res = parser.get();
  c.keep = res.keep_alive();
  const unsigned status = res.result_int();
  if (status == 200)
    fail(url_, "the server answers a range request with the whole file (200): serve the world from a server with byte "
               "ranges (Debian's nginx has them)");
  if (learn && status == 416) fail(url_, "is empty: not a world file");
  if (status != 206)
    fail(url_, "the server answered " + std::to_string(status) + " " + std::string(res.reason().data(), res.reason().size()) +
                   (status == 404 ? ": no file there; check the URL" : " to " + range));
  const std::string content_range = field(res, http::field::content_range);
  const auto cr = parse_content_range(content_range);
  if (!cr || cr->first != first || cr->last != last || res.body().size() != wanted)
    fail(url_, "asked for " + range + ", the server sent \"" + content_range + "\" with " +
                   std::to_string(res.body().size()) + " bytes");
  std::string validator = field(res, http::field::etag);
  if (validator.empty()) validator = field(res, http::field::last_modified);
  if (learn) {
    size_ = cr->total;
    validator_ = validator;
  } else if (cr->total != size_ || validator != validator_) {
    fail(url_, "the file changed on the server since it was opened (" + std::to_string(size_) + " → " + std::to_string(cr->total) +
                   " bytes, validator " + validator_ + " → " + validator + "); open the world again");
  }
  std::memcpy(dst, res.body().data(), wanted);
  requests_.fetch_add(1, std::memory_order_relaxed);
  bytes_.fetch_add(wanted, std::memory_order_relaxed);
  return true;
}

long HttpReadSource::read_at(void* dst, size_t bytes, uint64_t offset) {
  if (offset >= size_ || bytes == 0) return 0;
  const uint64_t last = std::min<uint64_t>(offset + bytes, size_) - 1;
  // A kept-alive connection the server closed meanwhile fails at once: each such one is dropped
  // and the request goes again, until a fresh connection answers or fails for real.
  // request() returns false only for a connection that had answered before, and the pool is
  // finite, so this ends.
  for (;;) {
    auto c = take_connection();
    if (request(*c, offset, last, dst, false)) {
      if (c->keep) give_back(std::move(c));
      return long(last - offset + 1);
    }
  }
}

HttpCounters HttpReadSource::counters() const {
  return {requests_.load(std::memory_order_relaxed), bytes_.load(std::memory_order_relaxed),
          connections_.load(std::memory_order_relaxed)};
}

}  // namespace cellwalk
