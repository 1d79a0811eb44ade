// HttpReadSource: a world file behind a plain web server, read by HTTP/1.1 range requests
// (issue 20, "served by a plain web server"; DESIGN.md "Out-of-core for real"). It is a
// ReadSource, the seam every read of the store goes through, so any command that opens a world
// can open `http://host:port/path.cww` instead of a path and every strategy walks it: each
// PageFile read becomes one `Range: bytes=a-b` request on a kept-alive connection, and the
// world file's page checksums check every byte that arrives. Debian's nginx serves ranges as
// it is; a server that ignores them (answers 200 with the whole file) is refused.
//
// Thread-safety: read_at may be called from any number of threads at once; each call takes a
// connection of its own from a pool (one is opened when none is idle).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cellwalk/store/page_file.hpp"

namespace cellwalk {

// Whether `path` names a world by URL ("http://..."): the store opens those over HTTP.
bool is_http_url(std::string_view path);

struct HttpUrl {
  std::string host;
  uint16_t port = 80;
  std::string target;  // "/path", with its query if any
};
// Parses "http://host[:port]/target". Throws Error naming the URL and what is wrong with it
// (https is refused: cellwalk has no TLS).
HttpUrl parse_http_url(std::string_view url);

// A Content-Range header's value "bytes first-last/total", as RFC 9110 §14.4 writes it for a
// 206 answer. nullopt unless it is exactly that, with first <= last < total.
struct ContentRange {
  uint64_t first = 0, last = 0, total = 0;
};
std::optional<ContentRange> parse_content_range(std::string_view value);

struct HttpCounters {
  uint64_t requests = 0;     // range requests answered
  uint64_t bytes = 0;        // body bytes received
  uint64_t connections = 0;  // connections opened (a dropped keep-alive costs one more)
};

class HttpReadSource final : public ReadSource {
 public:
  // Opens a connection and learns the file's size and validator (ETag, else Last-Modified) with
  // a one-byte range request. Throws Error naming the URL when the server cannot be reached,
  // answers other than 206, or does not serve ranges. `timeout_ms` bounds each request.
  explicit HttpReadSource(const std::string& url, uint32_t timeout_ms = 10000);
  ~HttpReadSource() override;
  HttpReadSource(const HttpReadSource&) = delete;
  HttpReadSource& operator=(const HttpReadSource&) = delete;

  // One range request for [offset, offset + bytes) clipped to the file. Returns the bytes read
  // (0 at the end of the file). Throws Error naming the URL and the range when the server fails,
  // answers another range, or the file changed since it was opened (its size or validator).
  long read_at(void* dst, size_t bytes, uint64_t offset) override;
  uint64_t size() const override { return size_; }
  const std::string& name() const override { return url_; }

  HttpCounters counters() const;

 private:
  struct Connection;
  std::unique_ptr<Connection> take_connection();
  void give_back(std::unique_ptr<Connection> c);
  // One request on `c`; copies the body into dst. Returns false when the connection turned out
  // to be closed before any answer (a kept-alive connection the server dropped): retry anew.
  bool request(Connection& c, uint64_t first, uint64_t last, void* dst, bool learn);

  std::string url_;
  HttpUrl where_;
  uint32_t timeout_ms_;
  uint64_t size_ = 0;
  std::string validator_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Connection>> idle_;
  std::atomic<uint64_t> requests_{0}, bytes_{0}, connections_{0};
};

}  // namespace cellwalk
