// libFuzzer target for what a browser (or anyone) may send `cellwalk serve --web`
// (include/cellwalk/net/web_listener.hpp): the input is written raw to a real WebListener on
// loopback, as an HTTP request (or an upgrade and WebSocket frames after it), then the client
// stops sending and reads until the server closes. The server must answer or close, never crash
// or hang; every WebSocket it opens is started and echoes nothing. The input is also a request
// target for web_file_for, whose answer must be "" or a file inside the served folder.
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <utility>

#include <boost/asio.hpp>

#include "cellwalk/net/web_listener.hpp"

namespace {

namespace asio = boost::asio;
using asio::ip::tcp;

class Server {
 public:
  Server() : root_((std::filesystem::temp_directory_path() / ("cellwalk-web-fuzz-" + std::to_string(::getpid()))).string()) {
    const std::filesystem::path root(root_);
    std::filesystem::create_directories(root / "src");
    std::ofstream(root / "index.html") << "<!doctype html>";
    std::ofstream(root / "src/main.js") << "export {};";
    canonical_ = std::filesystem::canonical(root_).string() + "/";
    listener_ = std::make_unique<cellwalk::net::WebListener>(io_, cellwalk::net::WebListenerOptions{0, "127.0.0.1", root_});
    listener_->accept([](std::shared_ptr<cellwalk::net::Connection> c) {
      c->start([](uint8_t, std::vector<uint8_t>) {}, [](const std::string&) {});
    });
    thread_ = std::thread([this] { io_.run(); });
  }
  uint16_t port() const { return listener_->port(); }
  const std::string& root() const { return root_; }
  const std::string& canonical() const { return canonical_; }

 private:
  std::string root_;
  std::string canonical_;
  asio::io_context io_;
  std::unique_ptr<cellwalk::net::WebListener> listener_;
  std::thread thread_;
};

Server& server() {
  static Server* s = new Server;  // lives for the fuzzer's whole run
  return *s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Server& s = server();
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::string file = cellwalk::net::web_file_for(s.root(), input);
  if (!file.empty() && file.compare(0, s.canonical().size(), s.canonical()) != 0) std::abort();

  asio::io_context io;
  tcp::socket socket(io);
  boost::system::error_code ec;
  socket.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), s.port()), ec);
  if (ec) std::abort();
  const timeval timeout{2, 0};  // a server that neither answers nor closes is a hang
  setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  // A browser waits for the answer to its request before it sends WebSocket frames: the input
  // goes in two parts, up to the end of its first request head, then (after the server's answer
  // head) the rest.
  const size_t head = input.find("\r\n\r\n");
  const size_t first = head == std::string::npos ? input.size() : head + 4;
  asio::write(socket, asio::buffer(input.data(), first), ec);
  if (first < input.size()) {
    asio::streambuf answer(1 << 16);
    asio::read_until(socket, answer, "\r\n\r\n", ec);
    asio::write(socket, asio::buffer(input.data() + first, input.size() - first), ec);
  }
  socket.shutdown(tcp::socket::shutdown_send, ec);
  char sink[4096];
  for (;;) {
    const ssize_t n = ::recv(socket.native_handle(), sink, sizeof sink, 0);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) std::abort();  // neither answered nor closed
      break;
    }
  }
  return 0;
}
