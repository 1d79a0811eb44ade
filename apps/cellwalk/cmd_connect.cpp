// cellwalk connect: a VDR streaming client (seed 004, ch. 4–6; docs/vdr.md "Client") walking one
// of the thesis's camera paths around the served model, headless, and its measures: frame time,
// unmodified frames, span, triangles, updates, batch latency and, given the model, accuracy.
#include <cstdio>
#include <memory>
#include <optional>

#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/vdr/vdr_walk.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "json_output.hpp"

namespace cellwalk::app {
namespace {

struct ConnectArgs {
  std::string address, model, traversal = "priority", units = "length", span = "1", predictor = "linear";
  int path = 1;
  vdr::VdrClientOptions client;
  double frame_ms = 30;
  bool json = false, prime = false;
};

void run_connect(ConnectArgs& a) {
  const size_t colon = a.address.rfind(':');
  if (colon == std::string::npos || colon == 0)
    fail(a.address, "is not HOST:PORT; give the address `cellwalk serve MODEL.cwvdr` printed");
  const std::string host = a.address.substr(0, colon);
  int port = 0;
  try {
    port = std::stoi(a.address.substr(colon + 1));
  } catch (const std::exception&) {
  }
  if (port <= 0 || port > 65535) fail(a.address, "names no port in 1-65535");
  a.client.hello.kind = vdr::parse_traversal(a.traversal);
  a.client.hello.units = a.units == "thesis" ? vdr::ErrorUnits::kThesis : vdr::ErrorUnits::kLength;
  a.client.adaptive_span = a.span == "auto";
  a.client.predictor = vdr::parse_predictor(a.predictor);
  if (!a.client.adaptive_span) {
    try {
      a.client.span = uint32_t(std::stoul(a.span));
    } catch (const std::exception&) {
      a.client.span = 0;
    }
    if (a.client.span < 1 || a.client.span > a.client.max_span)
      fail("--span " + a.span, "is neither auto nor a whole number of frames in 1-" + std::to_string(a.client.max_span));
  }
  std::optional<vdr::VdrModel> model;
  if (!a.model.empty()) model = vdr::read_vdr_file(a.model);
  vdr::VdrClient client(host, uint16_t(port), a.client);
  if (model && model->pm.vsplit_count() != client.welcome().vsplits)
    fail(a.model, "is not the model the server serves (" + std::to_string(client.welcome().vsplits) + " vsplits there)");
  vdr::VdrWalkOptions walk;
  walk.frame_ms = a.frame_ms;
  walk.reference = model ? &*model : nullptr;
  walk.prime = a.prime;
  const vdr::VdrWalkResult r = vdr::walk_vdr(client, a.client, vdr::thesis_path(a.path, client.welcome().bounds), walk);
  nlohmann::ordered_json j = {{"server", a.address},
                              {"path", a.path},
                              {"frames", r.frames.size()},
                              {"start_up", {{"batches", r.prime.batches}, {"converged", r.prime.converged}, {"ms", r.prime.ms}}},
                              {"mean_frame_ms", r.mean_frame_ms},
                              {"mean_update_ms", r.mean_update_ms},
                              {"unmodified_share", r.unmodified_share},
                              {"largest_span", r.stats.largest_span},
                              {"mean_triangles", r.mean_triangles},
                              {"mean_updates", r.mean_ops},
                              {"batch_p50_ms", r.batch_p50_ms},
                              {"batch_p99_ms", r.batch_p99_ms},
                              {"bytes_received", r.stats.bytes_received},
                              {"accuracy", r.mean_accuracy < 0 ? nlohmann::ordered_json() : nlohmann::ordered_json(r.mean_accuracy)}};
  nlohmann::ordered_json samples = nlohmann::ordered_json::array();
  for (size_t i = 0; i < r.frames.size(); ++i)
    if (r.frames[i].accuracy >= 0) samples.push_back({i, r.frames[i].accuracy});
  j["accuracy_by_frame"] = samples;
  if (a.json) {
    print_json("connect", j);
    return;
  }
  if (a.prime)
    std::printf("start-up: %u batches in %.0f ms, %u triangles%s\n", r.prime.batches, r.prime.ms, r.prime.triangles,
                r.prime.converged ? "" : " (stopped at --prime-batches before the view was refined)");
  std::printf("%zu frames of path %d from %s: %.1f ms a frame (T_u %.2f ms), %.1f%% unmodified, span up to %u\n",
              r.frames.size(), a.path, a.address.c_str(), r.mean_frame_ms, r.mean_update_ms, 100 * r.unmodified_share,
              r.stats.largest_span);
  std::printf("  %.0f triangles and %.0f updates a frame; batches p50 %.1f ms, p99 %.1f ms; %llu bytes received\n",
              r.mean_triangles, r.mean_ops, r.batch_p50_ms, r.batch_p99_ms, (unsigned long long)r.stats.bytes_received);
  if (r.mean_accuracy >= 0) std::printf("  accuracy against the sequential reference: %.1f%%\n", 100 * r.mean_accuracy);
}

}  // namespace

void register_connect(CLI::App& root) {
  auto* cmd = root.add_subcommand("connect", "Walk a served VDR model as a view-dependent streaming client (headless) and report");
  auto a = std::make_shared<ConnectArgs>();
  cmd->add_option("address", a->address, "HOST:PORT of `cellwalk serve MODEL.cwvdr`")->required();
  cmd->add_option("--path", a->path, "The thesis's camera path: 1 (approach and scans, 180 frames) or 2 (approach and orbit, 194)")
      ->capture_default_str()->check(integer_in(1, 2));
  cmd->add_option("--model", a->model, "The served .cwvdr, to measure accuracy against the sequential reference run");
  cmd->add_option("--traversal", a->traversal, "priority, linear or constant")->capture_default_str()
      ->check(CLI::IsMember({"priority", "linear", "constant"}));
  cmd->add_option("--units", a->units, "Error units: thesis (raw quadric error) or length (its square root)")->capture_default_str()
      ->check(CLI::IsMember({"thesis", "length"}));
  cmd->add_option("--budget", a->client.budget, "B, the client's triangle budget")->capture_default_str()->check(integer_in(1, 1'000'000'000));
  cmd->add_option("-n,--ops", a->client.n, "N, ops per direction per frame")->capture_default_str()->check(integer_in(1, 65535));
  cmd->add_option("--tau", a->client.tau, "τ, screen-space tolerance as a fraction of the viewport")->capture_default_str()->check(number_in(1e-6, 1));
  cmd->add_option("--span", a->span, "Frames ahead a request is for: a number (1: LAN) or auto (Eq. 6.3.1)")->capture_default_str();
  cmd->add_option("--predictor", a->predictor, "How a request's view is predicted: linear (the thesis's), turn, or none")
      ->capture_default_str()->check(CLI::IsMember({"linear", "turn", "none"}));
  cmd->add_option("--max-span", a->client.max_span, "The largest span auto may choose")->capture_default_str()->check(integer_in(1, 64));
  cmd->add_flag("--sequential", a->client.sequential, "Wait for each frame's batch (the thesis's sequential client)");
  cmd->add_flag("--gradual-fill", a->client.gradual_fill, "Fill the pipeline one request a frame, each for the frame it will arrive by");
  cmd->add_option("--jump-catch-up", a->client.jump_catch_up, "Extra requests sent after a jump of the view (0: none)")->capture_default_str()->check(integer_in(0, 64));
  cmd->add_flag("--catch-up-as-start-up", a->client.catch_up_as_start_up,
                "With --prime and --jump-catch-up: send at least as many catch-up requests as start-up took batches");
  cmd->add_flag("--prime", a->prime, "Refine the first view before frame 0, as a viewer's loading screen would");
  cmd->add_option("--prime-batches", a->client.prime_batches, "The most batches --prime takes")->capture_default_str()->check(integer_in(1, 1'000'000));
  cmd->add_flag("--lockstep", a->client.hello.lockstep, "Have the server check this client's mesh after every batch");
  cmd->add_flag("!--alarm-level", a->client.server_budget,
                "Keep under B by the thesis's alarm level B - 2Nf instead of letting the server hold B");
  cmd->add_option("--latency-ms", a->client.outgoing.latency_ms, "Delay added to every request (one way)")->capture_default_str()->check(number_in(0, 60000));
  cmd->add_option("--bandwidth-mbit", a->client.outgoing.bandwidth_mbit, "Rate of the requests in Mbit/s (0: unlimited)")->capture_default_str()->check(number_in(0, 1e6));
  cmd->add_option("--frame-ms", a->frame_ms, "Each frame lasts at least this (a display's pace)")->capture_default_str()->check(number_in(0, 10000));
  cmd->add_flag("--json", a->json, "Print the report as JSON");
  cmd->callback([a] { run_connect(*a); });
}

}  // namespace cellwalk::app
