// cellwalk serve: seed 004's servers over TCP (docs/protocol.md), many clients, until SIGINT/SIGTERM
// or --seconds: a world with visible sets over a grid (PVS streaming, ch. 7) or a VDR model
// (.cwvdr: view-dependent refinement, ch. 3–6).
#include <pthread.h>
#include <signal.h>

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <functional>
#include <memory>
#include <thread>
#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/pvs_stream/pvs_server.hpp"
#include "cellwalk/systems/vdr/vdr_server.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "json_output.hpp"

namespace cellwalk::app {
namespace {

// Waits for SIGINT or SIGTERM, or the deadline (0: none), then stops the server. The signals
// are blocked in every thread first, so only this one takes them.
std::thread stop_on_signal_or_deadline(std::function<void()> stop, double seconds) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return std::thread([stop, set, seconds] {
    for (double waited = 0; seconds <= 0 || waited < seconds; waited += 0.2) {
      const timespec step{0, 200'000'000};
      if (sigtimedwait(&set, nullptr, &step) > 0) break;
    }
    stop();
  });
}

// The page and the npm packages it imports must be there, or a browser gets a blank page.
void check_web_client(const std::string& root) {
  namespace fs = std::filesystem;
  if (!fs::is_regular_file(fs::path(root) / "index.html"))
    throw Error(root + ": no browser client here (no index.html); pass --web-root with cellwalk's web/ folder");
  for (const char* package : {"three", "meshoptimizer"})
    if (!fs::is_directory(fs::path(root) / "node_modules" / package))
      throw Error(root + ": the browser client's npm package " + package + " is missing; run `npm ci` in " + root +
                  " (scripts/setup does)");
}

bool is_vdr_model(const std::string& path) { return path.size() > 6 && path.ends_with(".cwvdr"); }

struct ServeArgs {
  std::string input;
  uint16_t port = 0;
  bool web = false;
  uint16_t web_port = 0;
  std::string web_root;
  net::LinkShape link;
  double seconds = 0, idle_s = 600;
  uint32_t max_sessions = 256;
  bool json = false, quiet = false;
};

std::function<void(const std::string&)> session_log(const ServeArgs& a) {
  if (a.quiet) return {};
  return [](const std::string& line) { std::fprintf(stderr, "cellwalk serve: %s\n", line.c_str()); };
}

void serve_vdr(const ServeArgs& a) {
  const vdr::VdrModel model = vdr::read_vdr_file(a.input);
  vdr::VdrServerOptions options;
  options.port = a.port;
  options.link = a.link;
  options.log = session_log(a);
  options.max_sessions = a.max_sessions;
  options.idle = std::chrono::milliseconds(int64_t(a.idle_s * 1000));
  vdr::VdrServer server(model, options);
  std::printf("serving %s (%u base triangles, %u vsplits) on 127.0.0.1:%u\n", a.input.c_str(),
              model.pm.base_triangle_count, model.pm.vsplit_count(), unsigned(server.port()));
  std::fflush(stdout);
  std::thread stopper = stop_on_signal_or_deadline([&server] { server.stop(); }, a.seconds);
  server.run();
  stopper.join();
  const vdr::VdrServerStats s = server.stats();
  if (a.json) {
    const nlohmann::ordered_json j = {{"port", server.port()},
                                      {"sessions", s.sessions_opened},
                                      {"dropped", s.sessions_dropped},
                                      {"refused", s.sessions_refused},
                                      {"batches", s.batches},
                                      {"ops", s.ops},
                                      {"bytes_sent", s.bytes_sent},
                                      {"traversal_ms", s.traversal_ms},
                                      {"peak_session_bytes", s.peak_session_bytes},
                                      {"model_bytes", s.model_bytes}};
    print_json("serve", j);
    return;
  }
  std::printf("served %llu sessions (%llu dropped, %llu refused), %llu batches, %llu ops, %llu bytes\n", (unsigned long long)s.sessions_opened,
              (unsigned long long)s.sessions_dropped, (unsigned long long)s.sessions_refused, (unsigned long long)s.batches, (unsigned long long)s.ops,
              (unsigned long long)s.bytes_sent);
}

}  // namespace

void register_serve(CLI::App& root) {
  auto* cmd = root.add_subcommand("serve", "Serve a world to PVS streaming clients, or a VDR model to view-dependent clients (TCP)");
  auto a = std::make_shared<ServeArgs>();
  cmd->add_option("input", a->input,
                  "World file (.cww) with visible sets over a grid (`cellwalk pvs --cells grid:S`), or a VDR model "
                  "(.cwvdr, `cellwalk vdr-build`)")->required();
  cmd->add_option("--port", a->port, "TCP port on 127.0.0.1 (0: a free one, printed)")->capture_default_str()->check(integer_in(0, 65535));
  cmd->add_option("--latency-ms", a->link.latency_ms, "Delay added to every reply (one way)")->capture_default_str()->check(number_in(0, 60000));
  cmd->add_option("--bandwidth-mbit", a->link.bandwidth_mbit, "Rate of the replies in Mbit/s (0: unlimited)")->capture_default_str()->check(number_in(0, 1e6));
  cmd->add_option("--seconds", a->seconds, "Stop after this many seconds (0: at SIGINT or SIGTERM)")->capture_default_str()->check(number_in(0, 1e9));
  cmd->add_option("--max-sessions", a->max_sessions, "VDR: sessions at once; one more is told the server is full")
      ->capture_default_str()->check(integer_in(1, 1'000'000));
  cmd->add_option("--idle-s", a->idle_s, "VDR: drop a session that sends nothing for this long (0: never)")
      ->capture_default_str()->check(number_in(0, 1e6));
  auto* web = cmd->add_flag("--web", a->web, "Also serve the browser client: a page and WebSockets on one HTTP port (docs/web.md)");
  cmd->add_option("--web-port", a->web_port, "HTTP port of --web on 127.0.0.1 (0: a free one, printed)")
      ->capture_default_str()->check(integer_in(0, 65535))->needs(web);
  cmd->add_option("--web-root", a->web_root, "The browser client's folder (default: $CELLWALK_WEB, else the source tree's web/)")
      ->needs(web);
  cmd->add_flag("--quiet", a->quiet, "Do not log sessions");
  cmd->add_flag("--json", a->json, "Print the summary as JSON when stopped");
  cmd->callback([a] {
    if (is_vdr_model(a->input)) {
      if (a->web) throw Error("--web serves worlds with visible sets, not VDR models: serve a .cww built with `cellwalk pvs --cells grid:S`");
      return serve_vdr(*a);
    }
    const World world(a->input);
    pvs_stream::PvsServerOptions options;
    options.port = a->port;
    options.link = a->link;
    options.log = session_log(*a);
    if (a->web) {
      options.web = true;
      options.web_port = a->web_port;
      options.web_root = a->web_root.empty() ? web_client_dir() : a->web_root;
      check_web_client(options.web_root);
    }
    pvs_stream::PvsServer server(world, options);
    const pvs_stream::Welcome grid = pvs_stream::grid_of(world);
    std::printf("serving %s (%zu objects, %u × %u cells) on 127.0.0.1:%u\n", a->input.c_str(), world.object_count(),
                grid.rows, grid.cols, unsigned(server.port()));
    if (a->web) std::printf("browser client at http://127.0.0.1:%u/\n", unsigned(server.web_port()));
    std::fflush(stdout);
    std::thread stopper = stop_on_signal_or_deadline([&server] { server.stop(); }, a->seconds);
    server.run();
    stopper.join();
    const pvs_stream::PvsServerStats s = server.stats();
    if (a->json) {
      nlohmann::ordered_json j = {{"port", server.port()},           {"sessions", s.sessions_opened},
                                  {"dropped", s.sessions_dropped},   {"fetches", s.fetches},
                                  {"objects_sent", s.objects_sent},  {"bytes_sent", s.bytes_sent}};
      if (a->web)
        j["web"] = {{"port", server.web_port()},
                    {"sessions", s.web_sessions},
                    {"files_served", s.web_files_served},
                    {"requests_refused", s.web_requests_refused}};
      print_json("serve", j);
      return;
    }
    std::printf("served %llu sessions (%llu dropped), %llu fetches, %llu objects, %llu bytes\n",
                (unsigned long long)s.sessions_opened, (unsigned long long)s.sessions_dropped,
                (unsigned long long)s.fetches, (unsigned long long)s.objects_sent, (unsigned long long)s.bytes_sent);
  });
}

}  // namespace cellwalk::app
