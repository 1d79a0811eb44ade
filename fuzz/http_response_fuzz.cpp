// libFuzzer target for what a web server may answer HttpReadSource
// (include/cellwalk/store/http_read_source.hpp): the input is the server's answer to every
// request, written by a real server on loopback, which then closes the connection. Opening the
// source and reading from it must succeed with the bytes asked for, or throw cellwalk::Error;
// never crash, hang (each request has a 200 ms timeout and the server closes after answering)
// or allocate without bound. The input's first line is also parsed as a URL and as a
// Content-Range value.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include <boost/asio.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/http_read_source.hpp"

namespace {

namespace asio = boost::asio;
using asio::ip::tcp;

// Answers each connection with the current answer, for the fuzzer's whole run.
class Server {
 public:
  Server() {
    thread_ = std::thread([this] {
      for (;;) {
        tcp::socket s(io_);
        boost::system::error_code ec;
        acceptor_.accept(s, ec);
        if (ec) continue;
        asio::streambuf head(1 << 16);
        asio::read_until(s, head, "\r\n\r\n", ec);
        std::string answer;
        {
          const std::lock_guard lock(mutex_);
          answer = answer_;
        }
        asio::write(s, asio::buffer(answer), ec);
        s.shutdown(tcp::socket::shutdown_both, ec);
      }
    });
    thread_.detach();  // lives as long as the fuzzer
  }
  void set(std::string answer) {
    const std::lock_guard lock(mutex_);
    answer_ = std::move(answer);
  }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(acceptor_.local_endpoint().port()) + "/w.cww"; }

 private:
  asio::io_context io_;
  tcp::acceptor acceptor_{io_, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)};
  std::mutex mutex_;
  std::string answer_;
  std::thread thread_;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Server* server = new Server();
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::string first = input.substr(0, input.find('\n'));
  if (const auto cr = cellwalk::parse_content_range(first); cr && (cr->first > cr->last || cr->last >= cr->total)) std::abort();
  try {
    cellwalk::parse_http_url(first);
  } catch (const cellwalk::Error&) {
  }
  server->set(input);
  try {
    cellwalk::HttpReadSource source(server->url(), 200);
    uint8_t buffer[64];
    const long got = source.read_at(buffer, sizeof buffer, 0);
    if (got < 0 || uint64_t(got) > std::min<uint64_t>(sizeof buffer, source.size())) std::abort();
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
