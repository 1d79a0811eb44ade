// A plain web server for experiments and tests (issue 20, "served by a plain web server"):
// Debian's nginx, started as a child process on 127.0.0.1 with a configuration of our own in a
// work folder (no system files are read or written), serving one folder with byte ranges and
// kept-alive connections; stopped and reaped when the object goes.
#pragma once

#include <cstdint>
#include <string>

#include <sys/types.h>

namespace cellwalk::bench {

// Where nginx is: $CELLWALK_NGINX, else nginx on PATH, else /usr/sbin/nginx; "" when none.
std::string find_nginx();

class WebServer {
 public:
  // Serves `root` (a folder) from a free port on 127.0.0.1; `work` holds its configuration, pid
  // and error log. Throws Error when nginx is missing ("run scripts/setup") or does not start
  // within a few seconds (with the last line of its error log).
  WebServer(const std::string& root, const std::string& work);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  uint16_t port() const { return port_; }
  // http://127.0.0.1:PORT/<relative>
  std::string url(const std::string& relative) const;
  // Resident memory of the nginx process, from /proc (its VmRSS), in bytes.
  uint64_t resident_bytes() const;

 private:
  bool start(const std::string& nginx, const std::string& root, const std::string& work);
  void stop();

  pid_t pid_ = -1;
  uint16_t port_ = 0;
  std::string work_;
};

}  // namespace cellwalk::bench
