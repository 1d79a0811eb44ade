// The web side of cellwalk's servers: static files and WebSockets on one HTTP port
// (docs/protocol.md, "WebSocket"; docs/web.md). Not from a seed: the browser client of issue 21.
#include "cellwalk/net/web_listener.hpp"

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <cctype>
#include <filesystem>
#include <optional>

#include "cellwalk/core/error.hpp"
#include "net/message_stream.hpp"

namespace cellwalk::net {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace fs = std::filesystem;
using tcp = asio::ip::tcp;

namespace {

constexpr auto kRequestTimeout = std::chrono::seconds(10);
constexpr uint32_t kRequestHeaderLimit = 8192;
constexpr const char* kWebSocketPath = "/ws";

// ---- Frames as binary WebSocket messages -------------------------------------------------

class WebSocketMessageStream final : public MessageStream {
 public:
  explicit WebSocketMessageStream(beast::tcp_stream stream) : ws_(std::move(stream)) {
    beast::get_lowest_layer(ws_).expires_never();  // the WebSocket keeps its own timeouts
    websocket::stream_base::timeout t = websocket::stream_base::timeout::suggested(beast::role_type::server);
    t.idle_timeout = websocket::stream_base::none();  // a walker may stand still; the server bounds what it holds
    ws_.set_option(t);
    ws_.binary(true);
  }
  asio::any_io_executor executor() override { return ws_.get_executor(); }

  template <class Request, class Handler>
  void accept(const Request& request, Handler handler) {
    ws_.async_accept(request, std::move(handler));
  }

  void read(uint32_t max_payload, std::chrono::milliseconds, ReadHandler handler) override {
    // A WebSocket message arrives whole: its size is bounded before it is buffered, and a peer
    // that stalls inside one holds at most that bound (beast has no per-message timer).
    ws_.read_message_max(kFrameHeaderBytes + size_t(max_payload));
    buffer_.clear();
    ws_.async_read(buffer_, [this, max_payload, handler = std::move(handler)](beast::error_code ec, size_t n) {
      if (ec == websocket::error::closed || ec == asio::error::eof) return handler({"the peer closed the connection"});
      if (ec == websocket::error::message_too_big)
        return handler({"a message of more than the " + std::to_string(max_payload) + " bytes allowed"});
      if (ec) return handler({"read failed: " + ec.message()});
      if (!ws_.got_binary()) return handler({"a text message: frames travel as binary WebSocket messages"});
      const auto data = buffer_.cdata();
      const std::span<const uint8_t> bytes(static_cast<const uint8_t*>(data.data()), data.size());
      if (bytes.size() < kFrameHeaderBytes) return handler({"a WebSocket message shorter than a frame header"});
      Read r;
      try {
        r.header = parse_frame_header(bytes.first(kFrameHeaderBytes), max_payload);
      } catch (const ProtocolError& e) {
        return handler({e.what()});
      }
      if (r.header.length != bytes.size() - kFrameHeaderBytes)
        return handler({"a WebSocket message of " + std::to_string(bytes.size()) + " bytes whose frame says " +
                        std::to_string(kFrameHeaderBytes + r.header.length)});
      r.payload.assign(bytes.begin() + kFrameHeaderBytes, bytes.end());
      r.wire_bytes = n;
      handler(std::move(r));
    });
  }

  void write(std::span<const uint8_t> frame, WriteHandler handler) override {
    ws_.async_write(asio::buffer(frame.data(), frame.size()), std::move(handler));
  }

  void close() override {
    beast::error_code ec;
    auto& socket = beast::get_lowest_layer(ws_).socket();
    socket.shutdown(tcp::socket::shutdown_both, ec);
    socket.close(ec);
  }

 private:
  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
};

const char* content_type(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json" || ext == ".map") return "application/json";
  if (ext == ".png") return "image/png";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".wasm") return "application/wasm";
  if (ext == ".txt" || ext == ".md") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

std::optional<std::string> percent_decoded(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '%') {
      out += s[i];
      continue;
    }
    if (i + 2 >= s.size() || !std::isxdigit(uint8_t(s[i + 1])) || !std::isxdigit(uint8_t(s[i + 2]))) return std::nullopt;
    out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
    i += 2;
  }
  return out;
}

}  // namespace

std::string web_file_for(const std::string& root, const std::string& target) {
  const std::optional<std::string> decoded = percent_decoded(target.substr(0, target.find_first_of("?#")));
  if (!decoded || decoded->empty() || (*decoded)[0] != '/') return "";
  std::string path = *decoded;
  if (path.find('\0') != std::string::npos || path.find('\\') != std::string::npos) return "";
  for (size_t start = 1; start <= path.size();) {
    const size_t end = std::min(path.find('/', start), path.size());
    if (path.compare(start, end - start, "..") == 0 && end - start == 2) return "";
    start = end + 1;
  }
  if (path.back() == '/') path += "index.html";
  std::error_code ec;
  const fs::path base = fs::canonical(root, ec);
  if (ec) return "";
  const fs::path file = fs::weakly_canonical(base / path.substr(1), ec);
  if (ec || !fs::is_regular_file(file, ec)) return "";
  const std::string b = base.string() + "/", f = file.string();
  if (f.compare(0, b.size(), b) != 0) return "";  // a link that leads out of the root
  return f;
}

// ---- The listener ------------------------------------------------------------------------

struct WebListener::Impl : std::enable_shared_from_this<WebListener::Impl> {
  asio::io_context& io;
  WebListenerOptions options;
  Listener listener;
  OnWebSocket on_websocket;
  WebListenerStats stats;
  bool closed = false;  // after close(): no connection is handed on, none accepted

  Impl(asio::io_context& i, WebListenerOptions o) : io(i), options(std::move(o)), listener(io, options.port, options.address) {}

  void refused(const std::string& line) {
    ++stats.refused;
    if (options.log) options.log("web: " + line);
  }
};

namespace {

// One HTTP connection: requests in turn (keep-alive) until one upgrades to a WebSocket.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, std::shared_ptr<WebListener::Impl> owner)
      : stream_(std::move(socket)), owner_(std::move(owner)) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(kRequestHeaderLimit);
    parser_->body_limit(0);
    stream_.expires_after(kRequestTimeout);
    http::async_read(stream_, buffer_, *parser_, [self = shared_from_this()](beast::error_code ec, size_t) {
      if (ec == http::error::end_of_stream || ec == asio::error::eof || ec == beast::error::timeout) return self->shut();
      if (ec) {
        self->owner_->refused("a malformed request (" + ec.message() + ")");
        return self->answer(http::status::bad_request, "a malformed request: " + ec.message() + "\n", false);
      }
      self->handle(self->parser_->release());
    });
  }

 private:
  using Request = http::request<http::empty_body>;

  void handle(Request request) {
    ++owner_->stats.requests;
    const std::string target(request.target());
    if (websocket::is_upgrade(request)) {
      if (target.substr(0, target.find('?')) != kWebSocketPath) {
        owner_->refused("a WebSocket asked for " + target + ", not " + kWebSocketPath);
        return answer(http::status::not_found, std::string("WebSockets are served on ") + kWebSocketPath + "\n", false);
      }
      if (!same_origin(request)) {
        owner_->refused("a WebSocket from another site (Origin " + std::string(request[http::field::origin]) + ")");
        return answer(http::status::forbidden, "WebSockets are served to this server's own page\n", false);
      }
      return upgrade(std::move(request));
    }
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      owner_->refused(std::string(request.method_string()) + " " + target);
      return answer(http::status::method_not_allowed, "only GET and HEAD are served\n", request.keep_alive());
    }
    const std::string file = owner_->options.root.empty() ? "" : web_file_for(owner_->options.root, target);
    if (file.empty()) {
      owner_->refused("no file for " + target);
      return answer(http::status::not_found, "no such file: " + target + "\n", request.keep_alive());
    }
    serve_file(request, file);
  }

  // A browser names the page that opens a WebSocket: only this server's own page may (another
  // site's script could otherwise stream the world from a server on the user's machine). Tools
  // that send no Origin are let in.
  static bool same_origin(const Request& request) {
    const auto origin = request.find(http::field::origin);
    if (origin == request.end()) return true;
    const std::string host(request[http::field::host]);
    return !host.empty() && (origin->value() == "http://" + host || origin->value() == "https://" + host);
  }

  void serve_file(const Request& request, const std::string& file) {
    http::file_body::value_type body;
    beast::error_code ec;
    body.open(file.c_str(), beast::file_mode::scan, ec);
    if (ec) {
      owner_->refused("cannot read " + file + " (" + ec.message() + ")");
      return answer(http::status::not_found, "cannot read " + std::string(request.target()) + "\n", request.keep_alive());
    }
    if (body.size() > owner_->options.max_file_bytes) {
      owner_->refused(file + " is larger than " + std::to_string(owner_->options.max_file_bytes) + " bytes");
      return answer(http::status::payload_too_large, "the file is too large to serve\n", request.keep_alive());
    }
    const uint64_t size = body.size();
    auto response = std::make_shared<http::response<http::file_body>>(
        std::piecewise_construct, std::make_tuple(std::move(body)), std::make_tuple(http::status::ok, request.version()));
    response->set(http::field::content_type, content_type(file));
    response->set(http::field::cache_control, "no-cache");
    response->content_length(size);
    response->keep_alive(request.keep_alive());
    const bool head = request.method() == http::verb::head;
    ++owner_->stats.files_served;
    if (!head) owner_->stats.file_bytes += size;
    if (head) {
      auto header_only = std::make_shared<http::response<http::empty_body>>(response->base());
      header_only->content_length(size);
      return send(header_only, request.keep_alive());
    }
    send(response, request.keep_alive());
  }

  void answer(http::status status, const std::string& text, bool keep_alive) {
    auto response = std::make_shared<http::response<http::string_body>>(status, 11);
    response->set(http::field::content_type, "text/plain; charset=utf-8");
    response->body() = text;
    response->keep_alive(keep_alive);
    response->prepare_payload();
    send(response, keep_alive);
  }

  template <class Response>
  void send(std::shared_ptr<Response> response, bool keep_alive) {
    stream_.expires_after(kRequestTimeout);
    http::async_write(stream_, *response, [self = shared_from_this(), response, keep_alive](beast::error_code ec, size_t) {
      if (ec || !keep_alive) return self->shut();
      self->read();
    });
  }

  void upgrade(Request request) {
    auto ws = std::make_unique<WebSocketMessageStream>(std::move(stream_));
    WebSocketMessageStream* raw = ws.get();
    auto pending = std::make_shared<std::unique_ptr<WebSocketMessageStream>>(std::move(ws));
    auto held = std::make_shared<Request>(std::move(request));
    raw->accept(*held, [owner = owner_, pending, held](beast::error_code ec) {
      if (ec) return owner->refused("a WebSocket handshake failed (" + ec.message() + ")");
      if (owner->closed) return;
      ++owner->stats.websockets;
      auto connection = std::make_shared<Connection>(std::move(*pending), owner->options.link, owner->options.limits);
      if (owner->on_websocket) owner->on_websocket(std::move(connection));
    });
  }

  void shut() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_both, ec);
    stream_.close();
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  std::shared_ptr<WebListener::Impl> owner_;
};

}  // namespace

WebListener::WebListener(asio::io_context& io, WebListenerOptions options) {
  if (!options.root.empty() && !fs::is_directory(options.root))
    throw Error(options.root + ": no such folder to serve; pass the browser client's folder (web/) with --web-root");
  impl_ = std::make_shared<Impl>(io, std::move(options));
}

WebListener::~WebListener() { close(); }

uint16_t WebListener::port() const { return impl_->listener.port(); }

void WebListener::accept(OnWebSocket on_websocket) {
  impl_->on_websocket = std::move(on_websocket);
  // Weak: the listener is the Impl's, and its handler must not keep the Impl alive.
  impl_->listener.accept([weak = std::weak_ptr<Impl>(impl_)](tcp::socket socket) {
    if (auto owner = weak.lock(); owner && !owner->closed) std::make_shared<HttpSession>(std::move(socket), std::move(owner))->read();
  });
}

void WebListener::close() {
  impl_->closed = true;
  impl_->on_websocket = nullptr;
  impl_->listener.close();
}

const WebListenerStats& WebListener::stats() const { return impl_->stats; }

}  // namespace cellwalk::net
