// Seed 004 (Zheng), §4.5, §5.4 and §6.2–6.3 as a strategy: the VDR client's RENDER procedure
// driven by the walk's frames (docs/vdr.md, "The vdr strategy").
#include "cellwalk/systems/vdr_client/vdr_strategy.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <optional>
#include <thread>
#include <tuple>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/vdr/vdr_file.hpp"
#include "cellwalk/systems/vdr/vdr_server.hpp"
#include "cellwalk/systems/vdr/vdr_walk.hpp"
#include "core/stopwatch.hpp"
#include "strategy/strategy_config.hpp"

namespace cellwalk {

namespace {
using Clock = std::chrono::steady_clock;
// Catch-up requests after a jump (as `cellwalk bench vdr`'s "ours"): past convergence they come
// back empty.
constexpr uint32_t kJumpCatchUp = 16;
}  // namespace

bool is_vdr_strategy_name(const std::string& name) { return strategy_base(name) == "vdr"; }

VdrStrategyConfig parse_vdr_strategy_name(const std::string& name) {
  if (!is_vdr_strategy_name(name)) fail("strategy \"" + name + "\"", "not a VDR name (vdr[:key=value,...])");
  VdrStrategyConfig c;
  c.client.predictor = vdr::Predictor::kTurn;
  c.client.adaptive_span = true;
  c.client.max_span = 24;
  bool link_given = false;
  for_each_strategy_setting(name, [&](const StrategySetting& s) {
    if (s.key == "model") c.model = s.value;
    else if (s.key == "server") std::tie(c.host, c.port) = s.host_port("HOST:PORT of `cellwalk serve MODEL.cwvdr`");
    else if (s.key == "latency_ms") {
      c.latency_ms = s.number(0, 60000);
      link_given = true;
    } else if (s.key == "traversal") {
      s.choice({"priority", "linear", "constant"});
      c.client.hello.kind = vdr::parse_traversal(s.value);
    } else if (s.key == "budget") c.client.budget = uint32_t(s.whole(1, 1'000'000'000));
    else if (s.key == "ops") c.client.n = uint32_t(s.whole(1, 65535));
    else if (s.key == "tau") c.client.tau = float(s.number(1e-6, 1));
    else if (s.key == "span" && s.value == "auto") c.client.adaptive_span = true;
    else if (s.key == "span") {
      c.client.adaptive_span = false;
      c.client.span = uint32_t(s.whole(1, int(c.client.max_span)));
    } else if (s.key == "predictor") {
      s.choice({"none", "linear", "turn"});
      c.client.predictor = vdr::parse_predictor(s.value);
    } else if (s.key == "client") {
      s.choice({"ours", "thesis"});
      c.ours = s.value == "ours";
    } else if (s.key == "pace") c.pace = s.whole(0, 1) != 0;
    else s.unknown("model, server, latency_ms, traversal, budget, ops, tau, span, predictor, client, pace");
  });
  if (!c.host.empty() && link_given)
    fail("strategy \"" + name + "\"", "latency_ms shapes the link of the strategy's own server; shape a running server with "
                                      "`cellwalk serve --latency-ms` (the client's side: `cellwalk connect --latency-ms`)");
  c.client.server_budget = c.ours;
  c.client.gradual_fill = c.ours;
  c.client.jump_catch_up = c.ours ? kJumpCatchUp : 0;
  c.client.catch_up_as_start_up = c.ours;
  c.client.outgoing.latency_ms = c.latency_ms;
  return c;
}

struct VdrStrategy::Impl {
  VdrStrategyConfig config;
  std::string model_file;
  vdr::VdrModel model;
  std::unique_ptr<vdr::VdrServer> server;  // the strategy's own (config.host empty)
  std::thread server_thread;
  std::unique_ptr<vdr::VdrClient> client;
  Mesh drawn;            // the client's mesh as the renderer takes it, this frame
  // A world of one object is that object, drawn with its id and colour, so compare matches it
  // with the truth's; the model of a world of many is one patch of all of them. Transient: the
  // renderer uploads the changing mesh each frame and keeps no copy.
  DrawItem item{0, 0, rgba8(200, 190, 170), DrawKind::kPatch, true};
  bool started = false;     // prime() was called (once, even if it failed)
  double last_update_ms = 0;  // the last frame's T_u
  vdr::VdrPrimeReport prime;
  uint64_t peak = 0;
  std::optional<Clock::time_point> epoch, last_frame;  // wall time of path time 0; of the last select

  ~Impl() {
    client.reset();  // closes the session before its server stops
    if (server) server->stop();
    if (server_thread.joinable()) server_thread.join();
  }

  std::string where() const {
    return "vdr (" + (config.host.empty() ? std::string("its own server") : config.host + ":" + std::to_string(config.port)) + ")";
  }

  static std::string default_model(const World& world) {
    std::filesystem::path p(world.file().path());
    if (p.extension() != ".cww") fail("strategy vdr", "give the model: vdr:model=FILE.cwvdr (`cellwalk vdr-build`)");
    return p.replace_extension(".cwvdr").string();
  }

  // The model must be the world's: the same bounds, to a thousandth of the diagonal.
  void check_model(const World& world) const {
    const Aabb& w = world.info().bounds;
    const float tolerance = 1e-3f * std::max(glm::length(w.size()), 1e-6f);
    const float off = std::max(glm::length(w.min - model.bounds.min), glm::length(w.max - model.bounds.max));
    if (!(off <= tolerance))
      fail(model_file, "is not this world's model (its bounds differ from " + world.file().path() +
                           "'s by " + std::to_string(off) + "); build both from one file: cellwalk import M -o W.cww "
                           "and cellwalk vdr-build M -o W.cwvdr");
  }

  void start() {
    std::string host = config.host;
    uint16_t port = config.port;
    if (host.empty()) {
      vdr::VdrServerOptions so;
      so.link.latency_ms = config.latency_ms;
      server = std::make_unique<vdr::VdrServer>(model, so);
      server_thread = std::thread([this] { server->run(); });
      host = "127.0.0.1";
      port = server->port();
    }
    client = std::make_unique<vdr::VdrClient>(host, port, config.client);
    if (client->welcome().vsplits != model.pm.vsplit_count())
      fail(where(), "serves another model (" + std::to_string(client->welcome().vsplits) + " vsplits; " + model_file +
                        " has " + std::to_string(model.pm.vsplit_count()) + "); serve " + model_file + " there");
  }

  // The view cone's half-angle α is the frustum diagonal's (the bench's camera, inverted).
  static float alpha_of(const Camera& c) {
    const double half_y = double(c.fov_y_deg) * std::numbers::pi / 360;
    return float(std::atan(std::tan(half_y) * std::sqrt(1.0 + double(c.aspect) * double(c.aspect))));
  }

  void pace(double time) {
    if (!config.pace || !epoch) return;
    std::this_thread::sleep_until(*epoch + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(time)));
  }

  uint64_t resident() const {
    uint64_t b = client->mesh().render_bytes() + client->mesh().aux_bytes() + drawn.positions.size() * 12 +
                 drawn.normals.size() * 12 + drawn.indices.size() * 4;
    if (server) {
      const vdr::VdrServerStats s = server->stats();
      b += s.model_bytes + s.peak_session_bytes;
    }
    return b;
  }
};

VdrStrategy::VdrStrategy(const World& world, const VdrStrategyConfig& config, const StrategyOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.config = config;
  if (options.memory_budget_bytes > 0)
    fail("strategy vdr", "takes no memory budget yet; its mesh is bounded by budget=B triangles (vdr:budget=B)");
  s.model_file = config.model.empty() ? Impl::default_model(world) : config.model;
  if (!std::filesystem::exists(s.model_file))
    fail(s.model_file, "no such VDR model; build it from the world's source: cellwalk vdr-build MODEL -o " + s.model_file);
  s.model = vdr::read_vdr_file(s.model_file);
  s.check_model(world);
  if (world.object_count() == 1) s.item = {0, 0, world.object(0).color, DrawKind::kObject, true};
  s.start();  // on a throw, ~Impl stops what started
}

VdrStrategy::~VdrStrategy() = default;

std::string VdrStrategy::name() const { return std::string("vdr:") + (impl_->config.ours ? "ours" : "thesis"); }

void VdrStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Impl& s = *impl_;
  s.pace(stats.time);
  const Stopwatch watch;
  const Vec3 eye = camera.position;
  // The aim point one model radius ahead: turning moves it by the angle times the radius, which
  // the jump rule (a step over 5 % of the diagonal) does not take for a jump.
  const Vec3 aim = eye + std::max(0.5f * glm::length(s.model.bounds.size()), 1e-6f) * camera.forward();
  s.client->set_alpha(Impl::alpha_of(camera));
  if (!s.started && s.config.ours) {
    s.started = true;
    s.prime = s.client->prime(eye, aim);  // start-up: the first view's cut
  }
  const auto now = Clock::now();
  if (s.last_frame)  // the frame before, less its T_u (rendered() adds it): for Eq. 6.3.1
    s.client->rendered(std::max(0.0, std::chrono::duration<double, std::milli>(now - *s.last_frame).count() - s.last_update_ms));
  s.last_frame = now;
  s.last_update_ms = s.client->frame(eye, aim).update_ms;
  const vdr::SelectiveMesh& m = s.client->mesh();
  s.drawn.positions = m.positions();
  s.drawn.normals = m.normals();
  s.drawn.indices = m.indices();
  items.assign(1, s.item);
  s.peak = std::max(s.peak, s.resident());
  if (!s.epoch) s.epoch = Clock::now() - std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(stats.time));
  stats.query_ms += watch.ms();
}

const Mesh* VdrStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  if (item.kind != impl_->item.kind || item.id != impl_->item.id) return nullptr;
  ++stats.cache_hits;
  return &impl_->drawn;
}

uint64_t VdrStrategy::resident_bytes() const { return impl_->resident(); }
uint64_t VdrStrategy::peak_resident_bytes() const { return std::max(impl_->peak, impl_->resident()); }

std::vector<std::pair<std::string, double>> VdrStrategy::walk_counters() const {
  const vdr::VdrClientStats c = impl_->client->stats();
  const std::vector<double> walked(c.batch_ms.begin() + std::min<size_t>(impl_->prime.batches, c.batch_ms.size()), c.batch_ms.end());
  return {{"batches", double(c.batches)},
          {"ops", double(c.ops)},
          {"bytes_received", double(c.bytes_received)},
          {"unmodified_frames", double(c.unmodified)},
          {"largest_span", double(c.largest_span)},
          {"batch_ms_p50", vdr::quantile(walked, 0.5)},
          {"startup_ms", impl_->prime.ms},
          {"triangles", double(impl_->client->mesh().triangle_count())}};
}

}  // namespace cellwalk
