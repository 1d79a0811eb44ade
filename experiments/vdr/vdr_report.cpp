// `cellwalk bench vdr`: seed 004 (Zheng), chapters 3–6 — Tables 3.2–3.3, 4.1–4.3, 5.1, 6.1 and
// Figs. 4.12 and 6.8 from our code, and many clients on one server (docs/results/vdr.md).
#include "experiments/vdr/vdr_report.hpp"

#include <algorithm>
#include <barrier>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <memory>
#include <numbers>
#include <thread>

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/core/process_memory.hpp"
#include "cellwalk/render/renderer.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/systems/vdr/vdr_server.hpp"
#include "cellwalk/systems/vdr/vdr_walk.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"
#include "experiments/common/bench_support.hpp"
#include "experiments/common/svg_plot.hpp"
#include "scene/shapes.hpp"

namespace cellwalk {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;
using bench::fixed;
using bench::Table;
using namespace vdr;

constexpr double kMiB = 1024.0 * 1024.0;

struct BenchModel {
  std::string name;
  uint64_t input_triangles = 0;
  VdrModel model;  // the mini-redundant DAG: what the server runs on
  double pm_s = 0;
};

// A sphere with bumps on three scales, about `triangles` of them: a large mesh with detail to
// refine everywhere, made here, so the bench needs no download.
Mesh bumpy_sphere(uint64_t triangles) {
  const int rings = std::max(8, int(std::sqrt(double(triangles) / 4)));
  Mesh m = shapes::ellipsoid(Vec3(1.0f), 2 * rings, rings);
  for (Vec3& p : m.positions) {
    const Vec3 d = glm::normalize(p - Vec3(0, 1, 0));  // the ellipsoid stands on y = 0
    const float bump = 0.05f * std::sin(9 * d.x) * std::sin(7 * d.y) + 0.02f * std::sin(31 * d.z + 3 * d.x) +
                       0.006f * std::sin(97 * d.y) * std::cos(83 * d.x);
    p = d * (1.0f + bump);
  }
  m.normals.clear();
  return m;
}

std::string model_path(const std::string& name) {
  if (fs::exists(name)) return name;
  const std::string cgal = "data/cgal/meshes/" + name;
  if (fs::exists(cgal)) return cgal;
  fail(name, "no such model here or in data/cgal/meshes; run scripts/setup to unpack libcgal-demo's meshes");
}

Mesh merged(const std::string& file) {
  Mesh all;
  for (const Object& o : import_model(file).objects) append(all, o.mesh);
  return all;
}

// The view cone's half-angle α is the frustum diagonal's: the image's vertical field follows.
Camera camera_of(const VdrFrame& f, const Aabb& bounds, float alpha, float aspect) {
  Camera c;
  c.position = f.eye;
  const Vec3 d = glm::normalize(f.aim - f.eye);
  c.yaw_deg = float(std::atan2(-d.x, -d.z) * 180 / std::numbers::pi);
  c.pitch_deg = float(std::asin(std::clamp(d.y, -1.0f, 1.0f)) * 180 / std::numbers::pi);
  c.aspect = aspect;
  c.fov_y_deg = float(2 * std::atan(std::tan(alpha) / std::sqrt(1 + aspect * aspect)) * 180 / std::numbers::pi);
  const float r = glm::length(bounds.size()) / 2;
  c.near_plane = std::max(1e-4f * r, 0.01f * r);
  c.far_plane = 20 * r + glm::length(f.eye - bounds.center());
  return c;
}

// Draws a selective mesh as one view-dependent patch, transient: each call uploads it anew.
class MeshPainter {
 public:
  MeshPainter(const VdrBenchParams& p, const Aabb& bounds) : p_(p), bounds_(bounds) {
    RenderSettings s;
    s.width = p.width;
    s.height = p.height;
    s.gpu_budget_bytes = 64ull << 20;
    renderer_ = std::make_unique<Renderer>(s);
  }
  double operator()(const SelectiveMesh& mesh, const VdrFrame& f) {
    const Stopwatch watch;
    mesh_.positions = mesh.positions();
    mesh_.normals = mesh.normals();
    mesh_.indices = mesh.indices();
    const DrawItem item{0, 0, rgba8(200, 190, 170), DrawKind::kPatch, true};
    renderer_->render(camera_of(f, bounds_, p_.alpha, float(p_.width) / float(p_.height)), std::span(&item, 1),
                      [this](const DrawItem&) { return &mesh_; });
    return watch.ms();
  }

 private:
  const VdrBenchParams& p_;
  Aabb bounds_;
  std::unique_ptr<Renderer> renderer_;
  Mesh mesh_;
};

// The path rotated by `angle` about the vertical axis through the model's centre.
std::vector<VdrFrame> turned(std::vector<VdrFrame> path, const Aabb& bounds, float angle) {
  const Vec3 c = bounds.center();
  const float cs = std::cos(angle), sn = std::sin(angle);
  const auto rot = [&](const Vec3& p) {
    const Vec3 d = p - c;
    return c + Vec3(cs * d.x + sn * d.z, d.y, -sn * d.x + cs * d.z);
  };
  for (VdrFrame& f : path) f = {rot(f.eye), rot(f.aim)};
  return path;
}

ErrorUnits units_of(const VdrBenchParams& p) { return p.units == "thesis" ? ErrorUnits::kThesis : ErrorUnits::kLength; }

// ---- Tables 3.2–3.3 ------------------------------------------------------------------------

struct Results {
  Table build, traversal, memory, lan, wan, spans, clients, alone;
  std::vector<PlotSeries> accuracy_412, wan_path;
  std::string drop_reasons;  // of the many clients' server
  Json summary = Json::object();
};

BenchModel build_model(const VdrBenchParams& p, const std::string& name, const Mesh& input, Results& r) {
  BenchModel b;
  b.name = name;
  b.input_triangles = input.triangle_count();
  Stopwatch clock;
  reset_peak_rss();
  const uint64_t rss_before = current_rss_bytes();
  b.model.pm = build_progressive_mesh(input, {.base_triangles = p.base_triangles}, name);
  b.pm_s = clock.lap_ms() / 1000;
  const uint64_t pm_peak = peak_rss_bytes() - std::min(peak_rss_bytes(), rss_before);
  for (const Vec3& v : b.model.pm.positions) b.model.bounds.extend(v);
  uint64_t edges[3] = {};
  double seconds[3] = {};
  for (DagKind kind : {DagKind::kFull, DagKind::kNonRedundant, DagKind::kMiniRedundant}) {
    clock.lap_ms();
    VsplitDag dag = build_vsplit_dag(b.model.pm, kind);
    seconds[int(kind)] = clock.lap_ms() / 1000;
    edges[int(kind)] = dag.edge_count();
    if (kind == DagKind::kMiniRedundant) b.model.dag = std::move(dag);
  }
  const double efficiency = 100.0 * double(edges[0] - edges[2]) / double(std::max<uint64_t>(1, edges[0] - edges[1]));
  r.build.push_back({name, std::to_string(b.input_triangles), std::to_string(b.model.pm.vsplit_count()), fixed(b.pm_s, 2),
                     fixed(pm_peak / kMiB, 0), fixed(seconds[0], 3), fixed(seconds[1], 3), fixed(seconds[2], 3),
                     std::to_string(edges[0]), std::to_string(edges[1]), std::to_string(edges[2]), fixed(efficiency, 1),
                     fixed(b.model.dag.byte_size() / 1024.0, 0)});
  return b;
}

// ---- Tables 4.1–4.3, Fig. 4.12: the traversals on one machine ---------------------------

using Triangles = std::vector<std::array<uint32_t, 3>>;

void traversals(const VdrBenchParams& p, const BenchModel& b, Results& r) {
  const std::vector<VdrFrame> path = thesis_path(1, b.model.bounds);
  std::map<uint32_t, std::unique_ptr<SelectiveMesh>> priority_at;  // the priority run's meshes, every 5 frames
  for (TraversalKind kind : {TraversalKind::kPriority, TraversalKind::kLinear, TraversalKind::kConstant}) {
    Traversal t(b.model, kind, units_of(p));
    const ProgressiveMesh& pm = b.model.pm;
    SelectiveMesh mesh(std::span(pm.positions).first(pm.base_vertex_count), std::span(pm.normals).first(pm.base_vertex_count), pm.base_indices);
    std::unique_ptr<MeshPainter> paint = p.render ? std::make_unique<MeshPainter>(p, b.model.bounds) : nullptr;
    double trav = 0, upd = 0, rnd = 0, tris = 0, updates = 0;
    uint32_t tris_160 = 0, front_160 = 0;
    uint64_t aux = 0, render_bytes = 0;
    PlotSeries accuracy{b.name + " " + traversal_name(kind), {}};
    std::vector<Op> ops;
    for (uint32_t i = 0; i < path.size(); ++i) {
      const int64_t alarm = int64_t(p.budget) - 2 * int64_t(p.n);
      const BudgetMode mode = int64_t(mesh.triangle_count()) > alarm ? BudgetMode::kBudget : BudgetMode::kFree;
      ops.clear();
      Stopwatch watch;
      t.manage({path[i].eye, path[i].aim, p.alpha, p.tau, mode, p.n}, ops, kMaxBatchBytes - kBatchHeaderBytes);
      trav += watch.lap_ms();
      for (const Op& op : ops) {
        const WireOp w = wire_op(pm, op);
        op.split ? mesh.vsplit(vsplit_op(w)) : mesh.ecol(vsplit_op(w));
      }
      upd += watch.lap_ms();
      if (paint) rnd += (*paint)(mesh, path[i]);
      tris += mesh.triangle_count();
      updates += double(ops.size());
      aux = std::max(aux, mesh.aux_bytes());
      render_bytes = std::max(render_bytes, mesh.render_bytes());
      if (i == 160) tris_160 = mesh.triangle_count(), front_160 = t.front_size();
      if (i % 5 != 0) continue;
      if (kind == TraversalKind::kPriority) priority_at[i] = std::make_unique<SelectiveMesh>(mesh);
      else accuracy.points.emplace_back(i, 100 * triangle_accuracy(mesh, *priority_at[i]));
    }
    const double n = double(path.size());
    double mean_accuracy = 100;
    if (!accuracy.points.empty()) {
      mean_accuracy = 0;
      for (const auto& [x, y] : accuracy.points) mean_accuracy += y / double(accuracy.points.size());
      r.accuracy_412.push_back(accuracy);
    }
    r.traversal.push_back({b.name, traversal_name(kind), fixed(trav / n, 2), fixed(upd / n, 2), p.render ? fixed(rnd / n, 2) : "—",
                           fixed(tris / n, 0), fixed(updates / n, 0), std::to_string(tris_160), std::to_string(front_160),
                           fixed(mean_accuracy, 1)});
    if (kind == TraversalKind::kPriority)
      r.memory.push_back({b.name, fixed(aux / kMiB, 3), fixed(render_bytes / kMiB, 3),
                          fixed(double(t.byte_size()) / kMiB, 3)});
  }
}

// ---- Over sockets ---------------------------------------------------------------------------

// A server on its own thread for one section; stopped when it goes.
class RunningServer {
 public:
  RunningServer(const VdrModel& model, double one_way_ms) {
    VdrServerOptions o;
    o.link.latency_ms = one_way_ms;
    o.max_sessions = 4096;
    o.log = [this](const std::string& line) {
      const size_t at = line.find(" dropped: ");
      if (at == std::string::npos) return;
      const std::lock_guard lock(mutex_);
      ++drops_[line.substr(at + 10)];
    };
    server_ = std::make_unique<VdrServer>(model, o);
    thread_ = std::thread([this] { server_->run(); });
  }
  ~RunningServer() { finish(); }
  // Stops the server; its stats then hold the serving thread's CPU time.
  VdrServerStats finish() {
    if (thread_.joinable()) {
      server_->stop();
      thread_.join();
    }
    return server_->stats();
  }
  uint16_t port() const { return server_->port(); }
  VdrServerStats stats() const { return server_->stats(); }
  // The serving thread's CPU time so far, ms. Thread-safe.
  double cpu_ms() const {
    clockid_t clock{};
    timespec t{};
    if (pthread_getcpuclockid(const_cast<std::thread&>(thread_).native_handle(), &clock) != 0 || clock_gettime(clock, &t) != 0) return 0;
    return double(t.tv_sec) * 1e3 + double(t.tv_nsec) / 1e6;
  }
  // Why sessions were dropped, and how many each reason.
  std::map<std::string, int> drops() const {
    const std::lock_guard lock(mutex_);
    return drops_;
  }

 private:
  mutable std::mutex mutex_;
  std::map<std::string, int> drops_;
  std::unique_ptr<VdrServer> server_;
  std::thread thread_;
};

// The many clients begin their walks this far apart (k after k times it), as users arrive: at
// once, the jumps of every path-1 client would coincide.
constexpr int kArrivalMs = 31;

// The many clients' nice value (the server's thread keeps 0).
constexpr int kClientNice = 10;

// Catch-up requests after a jump: past convergence they come back empty, so generous is cheap.
constexpr uint32_t kJumpCatchUp = 16;

// The thesis's client (linear prediction, the alarm level) or ours (turn, a server-held budget,
// the pipeline filled gradually, catch-up after jumps; walk_on primes it).
VdrClientOptions client_options(const VdrBenchParams& p, bool ours, double one_way_ms) {
  VdrClientOptions o;
  o.outgoing.latency_ms = one_way_ms;
  o.hello = {TraversalKind::kPriority, units_of(p), false};
  o.budget = p.budget;
  o.n = p.n;
  o.tau = p.tau;
  o.alpha = p.alpha;
  o.adaptive_span = true;
  o.predictor = ours ? Predictor::kTurn : Predictor::kLinear;
  o.server_budget = ours;
  o.gradual_fill = ours;
  o.jump_catch_up = ours ? kJumpCatchUp : 0;
  o.catch_up_as_start_up = ours;
  o.max_span = 24;
  return o;
}

VdrWalkResult walk_on(const VdrBenchParams& p, const BenchModel& b, uint16_t port, const VdrClientOptions& o,
                      const std::vector<VdrFrame>& path, double frame_ms, bool render, bool prime,
                      std::function<void()> after_start_up = {}, std::function<void()> before_reference = {}) {
  VdrClient client("127.0.0.1", port, o);
  VdrWalkOptions w;
  w.after_start_up = std::move(after_start_up);
  w.before_reference = std::move(before_reference);
  w.frame_ms = frame_ms;
  w.prime = prime;
  w.reference = &b.model;
  std::unique_ptr<MeshPainter> paint = render ? std::make_unique<MeshPainter>(p, b.model.bounds) : nullptr;
  if (paint) w.render = [&](const SelectiveMesh& m, const VdrFrame& f) { return (*paint)(m, f); };
  return walk_vdr(client, o, path, w);
}

double mean_of(const std::vector<double>& v) { return bench::mean(v); }

// Table 5.1: sequential against one-frame parallel on a LAN (frames unpaced: T is the work).
void lan(const VdrBenchParams& p, const BenchModel& b, Results& r) {
  const RunningServer server(b.model, p.lan_rtt / 2);
  for (bool sequential : {true, false}) {
    VdrClientOptions o = client_options(p, false, p.lan_rtt / 2);
    o.adaptive_span = false;
    o.span = 1;
    o.sequential = sequential;
    const VdrWalkResult w = walk_on(p, b, server.port(), o, thesis_path(1, b.model.bounds), 0.0, p.render, false);
    r.lan.push_back({b.name, sequential ? "sequential" : "parallel", fixed(w.mean_triangles, 0), fixed(w.mean_ops, 1),
                     fixed(mean_of(w.stats.batch_ms), 2), fixed(w.mean_update_ms, 2), fixed(w.mean_render_ms, 2),
                     fixed(w.mean_frame_ms, 2), fixed(100 * w.unmodified_share, 1), fixed(100 * w.mean_accuracy, 1)});
  }
}

// Table 6.1 and Fig. 6.8: each RTT, both paths, the thesis's client and ours; spans at one RTT.
void wan(const VdrBenchParams& p, const BenchModel& b, bool spans, Results& r) {
  for (double rtt : p.rtts) {
    const RunningServer server(b.model, rtt / 2);
    for (int path : {1, 2})
      for (bool ours : {false, true}) {
        const VdrClientOptions o = client_options(p, ours, rtt / 2);
        const VdrWalkResult w = walk_on(p, b, server.port(), o, thesis_path(path, b.model.bounds), p.frame_ms, p.render, ours);
        r.wan.push_back({b.name, fixed(rtt, 0), std::to_string(path), ours ? "ours" : "thesis",
                         ours ? fixed(w.prime.ms, 0) : "—", std::to_string(w.stats.largest_span), fixed(w.mean_frame_ms, 1), fixed(w.mean_render_ms, 1),
                         fixed(w.mean_triangles, 0), fixed(100 * w.mean_accuracy, 1), fixed(100 * w.unmodified_share, 1),
                         fixed(w.batch_p50_ms, 0)});
        r.summary["wan"].push_back({{"model", b.name}, {"rtt_ms", rtt}, {"path", path}, {"client", ours ? "ours" : "thesis"},
                                    {"accuracy", w.mean_accuracy}, {"frame_ms", w.mean_frame_ms},
                                    {"start_up_ms", w.prime.ms}});
        if (rtt == p.rtts.back() && path == 1) {
          PlotSeries s{b.name + (ours ? " ours" : " thesis"), {}};
          for (size_t i = 0; i < w.frames.size(); ++i)
            if (w.frames[i].accuracy >= 0) s.points.emplace_back(double(i), 100 * w.frames[i].accuracy);
          r.wan_path.push_back(s);
        }
      }
    if (!spans || rtt != p.rtts[std::min<size_t>(1, p.rtts.size() - 1)]) continue;
    for (uint32_t span : p.spans)
      for (bool ours : {false, true}) {
        VdrClientOptions o = client_options(p, ours, rtt / 2);
        o.adaptive_span = false;
        o.span = span;
        const VdrWalkResult w = walk_on(p, b, server.port(), o, thesis_path(1, b.model.bounds), p.frame_ms, p.render, ours);
        r.spans.push_back({b.name, fixed(rtt, 0), std::to_string(span), ours ? "ours" : "thesis", fixed(100 * w.unmodified_share, 1),
                           fixed(100 * w.mean_accuracy, 1), fixed(w.mean_frame_ms, 1)});
      }
  }
}

// Many clients on one server, each on its own path (path 1 or 2 turned about the model), ours,
// paced, not drawn; then a few of them alone.
void many(const VdrBenchParams& p, const BenchModel& b, Results& r) {
  if (p.clients <= 0) return;
  const auto path_of = [&](int k) {
    return turned(thesis_path(1 + k % 2, b.model.bounds), b.model.bounds, float(2 * std::numbers::pi * k / p.clients));
  };
  const VdrClientOptions o = client_options(p, true, p.clients_rtt / 2);
  std::vector<VdrWalkResult> crowd(size_t(p.clients));
  std::vector<std::string> failures(size_t(p.clients));
  VdrServerStats stats;
  struct WalkMark {
    std::chrono::steady_clock::time_point wall;
    double process_ms = 0, server_ms = 0;
  } walk_start, walk_end;
  {
    RunningServer server(b.model, p.clients_rtt / 2);
    // All start walking together once every one has started up, and no reference runs before
    // every walk has ended; the walks' wall and CPU times are taken there.
    const auto process_cpu_ms = [] {
      timespec t{};
      clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
      return double(t.tv_sec) * 1e3 + double(t.tv_nsec) / 1e6;
    };
    const auto mark = [&](WalkMark& m) {
      m.wall = std::chrono::steady_clock::now();
      m.process_ms = process_cpu_ms();
      m.server_ms = server.cpu_ms();
    };
    std::barrier started(p.clients, [&]() noexcept { mark(walk_start); });
    std::barrier walked(p.clients, [&]() noexcept { mark(walk_end); });
    std::vector<std::thread> threads;
    for (int k = 0; k < p.clients; ++k)
      threads.emplace_back([&, k] {
        bool at_start = false, at_end = false;
        try {
          crowd[k] = walk_on(p, b, server.port(), o, path_of(k), p.frame_ms, false, true,
                             [&] {
                               // The clients' frames share this machine's cores with the server
                               // and the network threads (started at the usual priority): at a
                               // lower one they do not starve them, as on machines of their own.
                               setpriority(PRIO_PROCESS, pid_t(syscall(SYS_gettid)), kClientNice);
                               at_start = true, started.arrive_and_wait();
                               std::this_thread::sleep_for(std::chrono::milliseconds(k * kArrivalMs));
                             },
                             [&] { at_end = true, walked.arrive_and_wait(); });
        } catch (const std::exception& e) {
          failures[k] = e.what();
          if (!at_start) started.arrive_and_drop();
          if (!at_end) walked.arrive_and_drop();
        }
      });
    for (std::thread& t : threads) t.join();
    // Every client has closed; the server sees each close within moments (a stop before then
    // would count the session as dropped).
    for (int k = 0; k < 1000 && server.stats().sessions_open > 0; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    stats = server.finish();
    for (const auto& [why, n] : server.drops()) r.drop_reasons += (r.drop_reasons.empty() ? "" : "; ") + std::to_string(n) + " × " + why;
  }
  const double seconds = std::chrono::duration<double>(walk_end.wall - walk_start.wall).count();
  const double server_share = (walk_end.server_ms - walk_start.server_ms) / 1000 / seconds;
  const double clients_share = (walk_end.process_ms - walk_start.process_ms) / 1000 / seconds - server_share;
  for (const std::string& f : failures)
    if (!f.empty()) throw Error("bench vdr: a client of " + std::to_string(p.clients) + " failed: " + f);
  std::vector<double> latencies, accuracy;
  uint64_t frames = 0, unmodified = 0;
  for (const VdrWalkResult& w : crowd) {
    latencies.insert(latencies.end(), w.stats.batch_ms.begin() + std::min<size_t>(w.prime.batches, w.stats.batch_ms.size()),
                     w.stats.batch_ms.end());  // the walk's: start-up's batches queue by design
    accuracy.push_back(100 * w.mean_accuracy);
    frames += w.frames.size();
    unmodified += w.stats.unmodified;
  }
  double worst_drop = 0;
  for (int j = 0; j < std::min(p.alone, p.clients); ++j) {
    const int k = j * p.clients / std::min(p.alone, p.clients);
    const RunningServer server(b.model, p.clients_rtt / 2);
    const VdrWalkResult w = walk_on(p, b, server.port(), o, path_of(k), p.frame_ms, false, true);
    const double drop = 100 * (w.mean_accuracy - crowd[k].mean_accuracy);
    worst_drop = std::max(worst_drop, drop);
    r.alone.push_back({std::to_string(k), std::to_string(1 + k % 2), fixed(100 * w.mean_accuracy, 1),
                       fixed(100 * crowd[k].mean_accuracy, 1), fixed(drop, 1)});
  }
  r.clients.push_back({b.name, std::to_string(p.clients), fixed(p.clients_rtt, 0), fixed(seconds, 1),
                       fixed(stats.cpu_ms / double(std::max<uint64_t>(1, frames)), 3), fixed(100 * server_share, 0),
                       fixed(100 * clients_share, 0),
                       fixed(double(stats.peak_session_bytes) / kMiB, 1), fixed(double(stats.peak_one_session_bytes) / kMiB, 2),
                       fixed(double(stats.model_bytes) / kMiB, 1), fixed(vdr::quantile(latencies, 0.5), 0),
                       fixed(vdr::quantile(latencies, 0.99), 0), fixed(*std::min_element(accuracy.begin(), accuracy.end()), 1),
                       fixed(bench::mean(accuracy), 1), fixed(100.0 * double(unmodified) / double(std::max<uint64_t>(1, frames)), 1),
                       std::to_string(stats.sessions_dropped), fixed(worst_drop, 1)});
  r.summary["clients"] = p.clients;
  r.summary["clients_worst_accuracy_drop"] = worst_drop;
  r.summary["clients_dropped"] = stats.sessions_dropped;
  r.summary["clients_server_cpu_share"] = server_share;
  r.summary["clients_cpu_share"] = clients_share;
}

// ---- The report -----------------------------------------------------------------------------

const std::vector<std::string> kBuildHeader = {"model", "triangles", "vsplits", "PM s", "PM peak MiB", "full s", "non s", "mini s",
                                               "full edges", "non edges", "mini edges", "mini efficiency %", "mini DAG KiB"};
const std::vector<std::string> kTraversalHeader = {"model", "traversal", "T_trav ms", "T_upd ms", "T_rnd ms", "triangles",
                                                   "updates", "triangles @160", "front nodes @160", "accuracy vs priority %"};
const std::vector<std::string> kMemoryHeader = {"model", "client aux MiB", "client render MiB", "server session MiB"};
const std::vector<std::string> kLanHeader = {"model", "client", "triangles", "updates", "T_g ms", "T_u ms", "T_r ms", "T ms",
                                             "unmodified %", "accuracy %"};
const std::vector<std::string> kWanHeader = {"model", "RTT ms", "path", "client", "start-up ms", "span (largest)", "frame ms", "T_r ms",
                                             "triangles", "accuracy %", "unmodified %", "T_g p50 ms"};
const std::vector<std::string> kSpanHeader = {"model", "RTT ms", "span", "client", "unmodified %", "accuracy %", "frame ms"};
const std::vector<std::string> kClientsHeader = {"model", "clients", "RTT ms", "walks s", "server CPU ms / client frame",
                                                 "server CPU % (walks)", "clients' CPU % (walks)", "sessions' peak MiB", "largest session MiB", "shared model MiB",
                                                 "T_g p50 ms", "T_g p99 ms", "accuracy min %", "accuracy mean %",
                                                 "unmodified %", "dropped", "worst drop vs alone (points)"};
const std::vector<std::string> kAloneHeader = {"client", "path", "accuracy alone %", "accuracy among all %", "drop (points)"};

std::string report(const VdrBenchParams& p, const Results& r, double minutes) {
  using bench::md_table;
  const auto figures = bench::Align::kFigures;
  std::string md = "# View-dependent rendering over networks (seed 004, Zheng, chapters 3–6)\n\n";
  md += "Generated by `" + p.command_line + "` on " + bench::utc_now() + " in " + fixed(minutes, 1) +
        " min; machine: " + bench::machine_info().dump() + ". Every figure comes from this one run. How the system works: "
        "[docs/vdr.md](../vdr.md); the wire format: [docs/protocol.md](../protocol.md).\n\n";
  md += "Settings: B = " + std::to_string(p.budget) + " triangles, N = " + std::to_string(p.n) + ", τ = " + fixed(100 * p.tau, 2) +
        " % of the viewport, α = " + fixed(p.alpha, 2) + " rad, error units `" + p.units + "`, base meshes of " +
        std::to_string(p.base_triangles) + " triangles; images " + std::to_string(p.width) + "×" + std::to_string(p.height) +
        (p.render ? " drawn by Mesa llvmpipe" : " not drawn (T_r = 0)") + ". The thesis's camera paths 1 (180 frames) and 2 "
        "(194), placed by each model's bounding sphere.\n\n";
  md += "## Tables 3.2–3.3: building the progressive mesh and the three DAGs\n\n" + md_table(kBuildHeader, r.build, figures);
  md += "\nThe thesis (Bunny, 69,451 triangles; a Pentium 4): full / non / mini 0.224 / 28.692 / 0.296 s, edges 171,122 / 62,891 / "
        "80,882, efficiency 83.4 %, 2,976 KB; efficiency 83.3–84.0 % on all six models. Efficiency = (full − mini) / (full − non).\n\n";
  md += "## Tables 4.1–4.3 and Fig. 4.12: the three traversals (path 1, one machine)\n\n"
        "Each frame: MANAGE-TRAVERSAL for the true view (BUDGET above B − 2N), the batch applied to the client's selective mesh, "
        "the mesh drawn. Accuracy: |T ∩ T_priority| / |T_priority| every 5 frames.\n\n" +
        md_table(kTraversalHeader, r.traversal, figures);
  md += "\nThe thesis (Bunny, ms: T_trav / T_upd / T_rnd; triangles / updates): priority 4.2 / 2.6 / 10.3, 36,258 / 335; linear "
        "2.6 / 2.6 / 10.2, 36,526 / 336; constant 0.8 / 2.0 / 9.9, 35,604 / 246. Linear reaches about 70 % of priority "
        "(Fig. 4.12).\n\n![accuracy against priority](vdr/fig-4-12.svg)\n\n";
  md += "Table 4.2 (largest along path 1; the thesis: bunny 0.595 MB aux, 0.898 MB render; 0.95 / 1.43 MB at 60k):\n\n" +
        md_table(kMemoryHeader, r.memory, figures);
  md += "\n## Table 5.1: sequential against one-frame parallel on a LAN (RTT " + fixed(p.lan_rtt, 1) +
        " ms, path 1, frames unpaced)\n\n" + md_table(kLanHeader, r.lan, figures);
  md += "\nThe thesis (Bunny): T 21.8 ms sequential, 14.2 ms parallel (T_g 8.3, T_u 2.4, T_r 10.4 / 11.6).\n\n";
  md += "## Table 6.1 and Fig. 6.8: RTT, span and prediction (frames paced at " + fixed(p.frame_ms, 0) + " ms)\n\n"
        "The span follows Eq. 6.3.1 (f = ⌈T_g / (T_u + T_r)⌉, smoothed). *Thesis*: first-order prediction and the alarm level "
        "B − 2Nf; *ours*: the coordinated-turn predictor with tangential acceleration (which does not extrapolate a "
        "jump), the budget held by the server, the pipeline filled one request a frame, " + std::to_string(kJumpCatchUp) +
        " catch-up requests after a jump (or as many as start-up took, if more), and start-up — the first view refined before frame 0, its time in the column "
        "(docs/vdr.md \"Beyond the thesis\"). Accuracy against the "
        "sequential run with the true views (primed too for a primed client).\n\n" + md_table(kWanHeader, r.wan, figures);
  md += "\nThe thesis (path 1, frame ms / accuracy): 80 ms PS 3 16.8 / 89.1 % (bunny) … 28.3 / 90.4 % (happy); 350 ms PS 12 "
        "16.7 / 77.7 % … 28.5 / 80.6 %.\n\n![accuracy along path 1 at the largest RTT](vdr/path1-accuracy.svg)\n\n";
  if (!r.spans.empty())
    md += "Fig. 6.8, spans fixed (path 1; the thesis, Happy at 170 ms: unmodified 86.6 % at PS 1, 41.7 % at 3, 3.3 % at 6; "
          "PS 6 most accurate):\n\n" + md_table(kSpanHeader, r.spans, figures);
  if (!r.clients.empty()) {
    md += "\n## Beyond the thesis: " + std::to_string(p.clients) + " clients on one server\n\n"
          "One server thread; each client on its own thread with its own path (path 1 or 2 turned about the model by k/" +
          std::to_string(p.clients) + " of a turn), our client, frames paced, not drawn; accuracy against each one's own "
          "sequential reference. All connect and start up at once; once every one has started up, client k begins its walk " +
          std::to_string(kArrivalMs) + "·k ms later (as users arrive); the references run once every walk has ended. The "
          "clients' frames run at nice " + std::to_string(kClientNice) + ", so that on this machine's two cores they do not "
          "starve the server's thread or the clients' network threads. Then " + std::to_string(p.alone) + " of them again, each alone on a fresh server.\n\n" +
          md_table(kClientsHeader, r.clients, figures) + "\n" + md_table(kAloneHeader, r.alone, figures) +
          "\nSessions the server dropped, by reason: " + (r.drop_reasons.empty() ? std::string("none") : r.drop_reasons) + ".\n";
  }
  return md;
}

}  // namespace

Json run_vdr_bench(const VdrBenchParams& p) {
  const auto start = bench::Clock::now();
  const fs::path out(p.out_dir), sub = out / "vdr";
  fs::create_directories(sub);
  std::unique_ptr<GlContext> gl = p.render ? GlContext::headless() : nullptr;
  Results r;
  std::vector<std::pair<std::string, Mesh>> inputs;
  for (const std::string& m : p.models) inputs.emplace_back(fs::path(m).stem().string(), merged(model_path(m)));
  if (p.large_triangles > 0) inputs.emplace_back("bumpy sphere", bumpy_sphere(p.large_triangles));
  const auto write_outputs = [&] {
    bench::write_csv(sub / "build.csv", kBuildHeader, r.build);
    bench::write_csv(sub / "traversals.csv", kTraversalHeader, r.traversal);
    bench::write_csv(sub / "lan.csv", kLanHeader, r.lan);
    bench::write_csv(sub / "wan.csv", kWanHeader, r.wan);
    bench::write_csv(sub / "spans.csv", kSpanHeader, r.spans);
    bench::write_csv(sub / "clients.csv", kClientsHeader, r.clients);
    LinePlot a{"Accuracy against the priority traversal (path 1)", "frame", "accuracy, %", false, 0, 100, 720, 440, r.accuracy_412};
    write_file_atomically((sub / "fig-4-12.svg").string(), render_svg(a));
    LinePlot w{"Accuracy along path 1 at the largest RTT", "frame", "accuracy, %", false, 0, 100, 720, 440, r.wan_path};
    write_file_atomically((sub / "path1-accuracy.svg").string(), render_svg(w));
    write_file_atomically((out / "vdr.md").string(), report(p, r, bench::seconds_since(start) / 60.0));
  };
  Progress progress("bench vdr", inputs.size());
  std::vector<BenchModel> models;
  for (size_t i = 0; i < inputs.size(); ++i) {
    BenchModel b = build_model(p, inputs[i].first, inputs[i].second, r);
    inputs[i].second = Mesh();
    traversals(p, b, r);
    lan(p, b, r);
    wan(p, b, i + 1 == inputs.size(), r);
    write_outputs();
    if (i == 0) models.push_back(std::move(b));
    progress.update(i + 1);
  }
  progress.finish();
  if (!models.empty()) many(p, models.front(), r);
  write_outputs();
  r.summary["models"] = inputs.size();
  r.summary["minutes"] = bench::seconds_since(start) / 60.0;
  return r.summary;
}

}  // namespace cellwalk
