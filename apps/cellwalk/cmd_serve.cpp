// cellwalk serve: the PVS streaming server (seed 004, ch. 7 over TCP; docs/protocol.md): one
// world with visible sets over a grid, many clients, until SIGINT/SIGTERM or --seconds.
#include <pthread.h>
#include <signal.h>

#include <cstdio>
#include <ctime>
#include <memory>
#include <thread>
#include <nlohmann/json.hpp>

#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/pvs_stream/pvs_server.hpp"
#include "checks.hpp"
#include "commands.hpp"

namespace cellwalk::app {
namespace {

// Waits for SIGINT or SIGTERM, or the deadline (0: none), then stops the server. The signals
// are blocked in every thread first, so only this one takes them.
std::thread stop_on_signal_or_deadline(pvs_stream::PvsServer& server, double seconds) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return std::thread([&server, set, seconds] {
    for (double waited = 0; seconds <= 0 || waited < seconds; waited += 0.2) {
      const timespec step{0, 200'000'000};
      if (sigtimedwait(&set, nullptr, &step) > 0) break;
    }
    server.stop();
  });
}

}  // namespace

void register_serve(CLI::App& root) {
  auto* cmd = root.add_subcommand("serve", "Serve a world's visible sets and geometry to PVS streaming clients (TCP)");
  struct Args {
    std::string world;
    pvs_stream::PvsServerOptions options;
    double seconds = 0;
    bool json = false, quiet = false;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("world", a->world, "World file (.cww) with visible sets over a grid (`cellwalk pvs --cells grid:S`)")->required();
  cmd->add_option("--port", a->options.port, "TCP port on 127.0.0.1 (0: a free one, printed)")->capture_default_str()->check(integer_in(0, 65535));
  cmd->add_option("--latency-ms", a->options.link.latency_ms, "Delay added to every reply (one way)")->capture_default_str()->check(number_in(0, 60000));
  cmd->add_option("--bandwidth-mbit", a->options.link.bandwidth_mbit, "Rate of the replies in Mbit/s (0: unlimited)")->capture_default_str()->check(number_in(0, 1e6));
  cmd->add_option("--seconds", a->seconds, "Stop after this many seconds (0: at SIGINT or SIGTERM)")->capture_default_str()->check(number_in(0, 1e9));
  cmd->add_flag("--quiet", a->quiet, "Do not log sessions");
  cmd->add_flag("--json", a->json, "Print the summary as JSON when stopped");
  cmd->callback([a] {
    const World world(a->world);
    if (!a->quiet)
      a->options.log = [](const std::string& line) { std::fprintf(stderr, "cellwalk serve: %s\n", line.c_str()); };
    pvs_stream::PvsServer server(world, a->options);
    const pvs_stream::Welcome grid = pvs_stream::grid_of(world);
    std::printf("serving %s (%zu objects, %u × %u cells) on 127.0.0.1:%u\n", a->world.c_str(), world.object_count(),
                grid.rows, grid.cols, unsigned(server.port()));
    std::fflush(stdout);
    std::thread stopper = stop_on_signal_or_deadline(server, a->seconds);
    server.run();
    stopper.join();
    const pvs_stream::PvsServerStats s = server.stats();
    if (a->json) {
      const nlohmann::ordered_json j = {{"port", server.port()},           {"sessions", s.sessions_opened},
                                        {"dropped", s.sessions_dropped},   {"fetches", s.fetches},
                                        {"objects_sent", s.objects_sent},  {"bytes_sent", s.bytes_sent}};
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    std::printf("served %llu sessions (%llu dropped), %llu fetches, %llu objects, %llu bytes\n",
                (unsigned long long)s.sessions_opened, (unsigned long long)s.sessions_dropped,
                (unsigned long long)s.fetches, (unsigned long long)s.objects_sent, (unsigned long long)s.bytes_sent);
  });
}

}  // namespace cellwalk::app
