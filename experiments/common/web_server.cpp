// Debian's nginx as a child process serving a folder on 127.0.0.1 (issue 20).
#include "experiments/common/web_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "cellwalk/core/error.hpp"

extern char** environ;

namespace cellwalk::bench {

namespace fs = std::filesystem;

namespace {

// A port the kernel had free a moment ago (nginx binds it next; a lost race is retried).
uint16_t free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) fail("web server", "cannot open a socket");
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
                  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0;
  ::close(fd);
  if (!ok) fail("web server", "cannot find a free port on 127.0.0.1");
  return ntohs(a.sin_port);
}

bool accepts(uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return false;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  ::close(fd);
  return ok;
}

std::string last_line(const std::string& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

// One worker in the foreground (master_process off: nothing to orphan, no user to switch to),
// everything under `work`, byte ranges and keep-alive as nginx serves static files by default.
std::string configuration(const std::string& root, const std::string& work, uint16_t port) {
  std::ostringstream c;
  c << "daemon off;\nmaster_process off;\nworker_processes 1;\n"
    << "pid " << work << "/nginx.pid;\nerror_log " << work << "/error.log warn;\n"
    << "events { worker_connections 1024; }\n"
    << "http {\n  access_log off;\n  keepalive_requests 1000000;\n  keepalive_timeout 120s;\n"
    << "  types { application/octet-stream cww; }\n  default_type application/octet-stream;\n";
  for (const char* temp : {"client_body", "proxy", "fastcgi", "uwsgi", "scgi"})
    c << "  " << temp << "_temp_path " << work << "/tmp;\n";
  c << "  server {\n    listen 127.0.0.1:" << port << ";\n    root " << root << ";\n  }\n}\n";
  return c.str();
}

}  // namespace

std::string find_nginx() {
  if (const char* env = std::getenv("CELLWALK_NGINX"); env && *env) return env;
  if (const char* path = std::getenv("PATH")) {
    std::stringstream dirs(path);
    for (std::string dir; std::getline(dirs, dir, ':');)
      if (!dir.empty() && ::access((dir + "/nginx").c_str(), X_OK) == 0) return dir + "/nginx";
  }
  return ::access("/usr/sbin/nginx", X_OK) == 0 ? "/usr/sbin/nginx" : "";
}

WebServer::WebServer(const std::string& root, const std::string& work) : work_(fs::absolute(work).string()) {
  const std::string nginx = find_nginx();
  if (nginx.empty()) fail("web server", "nginx is not installed; run scripts/setup (it installs Debian's nginx-light)");
  if (!fs::is_directory(root)) fail(root, "is not a folder to serve");
  fs::create_directories(work_ + "/tmp");
  for (int attempt = 0; attempt < 5; ++attempt)
    if (start(nginx, fs::absolute(root).string(), work_)) return;
  fail("web server", "nginx lost the race for a free port five times; try again");
}

bool WebServer::start(const std::string& nginx, const std::string& root, const std::string& work) {
  port_ = free_port();
  const std::string conf = work + "/nginx.conf", log = work + "/error.log";
  std::ofstream(conf) << configuration(root, work, port_);
  fs::remove(log);
  std::vector<std::string> args = {nginx, "-p", work + "/", "-e", log, "-c", conf};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  for (int fd : {0, 1, 2}) posix_spawn_file_actions_addopen(&actions, fd, "/dev/null", fd == 0 ? O_RDONLY : O_WRONLY, 0);
  const int rc = ::posix_spawn(&pid_, nginx.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) fail(nginx, "cannot be started (" + std::string(std::strerror(rc)) + ")");
  for (int i = 0; i < 250; ++i) {  // 5 s
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      const std::string why = last_line(log);
      if (why.find("Address already in use") != std::string::npos) return false;
      fail(nginx, "stopped at start: " + (why.empty() ? std::string("no error log") : why));
    }
    if (accepts(port_)) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  stop();
  fail(nginx, "did not listen on 127.0.0.1:" + std::to_string(port_) + " within 5 s (" + last_line(log) + ")");
}

void WebServer::stop() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGTERM);
  int status = 0;
  bool reaped = false;
  for (int i = 0; i < 100 && !reaped; ++i) {  // 2 s for a fast shutdown
    reaped = ::waitpid(pid_, &status, WNOHANG) == pid_;
    if (!reaped) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!reaped) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status, 0);
  }
  pid_ = -1;
}

WebServer::~WebServer() { stop(); }

std::string WebServer::url(const std::string& relative) const {
  return "http://127.0.0.1:" + std::to_string(port_) + "/" + relative;
}

uint64_t WebServer::resident_bytes() const {
  std::ifstream in("/proc/" + std::to_string(pid_) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::strtoull(line.c_str() + 6, nullptr, 10) * 1024;
  return 0;
}

}  // namespace cellwalk::bench
