// Seed 004 (Zheng), §4.5, Figs. 5.5 and 6.2, Eq. 6.3.1: the VDR streaming client (docs/vdr.md,
// "Client"; docs/protocol.md, "VDR streaming").
#include "cellwalk/systems/vdr/vdr_client.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>

#include <glm/gtc/quaternion.hpp>

#include "cellwalk/core/error.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk::vdr {

namespace asio = boost::asio;
using asio::ip::tcp;

namespace {
// TCP's SRTT gain: the span follows a smoothed T_g and frame time, not one late batch.
constexpr double kSmoothing = 1.0 / 8;
// Frames between span updates (the thesis updates f "periodically").
constexpr uint64_t kSpanPeriod = 8;

double smooth(double old_value, double sample) { return old_value < 0 ? sample : old_value + kSmoothing * (sample - old_value); }
}  // namespace

std::string predictor_name(Predictor p) {
  switch (p) {
    case Predictor::kNone: return "none";
    case Predictor::kLinear: return "linear";
    case Predictor::kTurn: return "turn";
  }
  return "?";
}

Predictor parse_predictor(const std::string& word) {
  for (Predictor p : {Predictor::kNone, Predictor::kLinear, Predictor::kTurn})
    if (predictor_name(p) == word) return p;
  fail("--predictor " + word, "is not a predictor: use none, linear or turn");
}

Vec3 predict_point(Predictor predictor, const Vec3& p2, const Vec3& p1, const Vec3& p0, uint32_t k) {
  const Vec3 v0 = p0 - p1;
  if (predictor == Predictor::kNone) return p0;
  if (predictor == Predictor::kLinear) return p0 + float(k) * v0;
  // The coordinated turn: the step v0 turned, each frame, by the rotation that took v1 to v0.
  const Vec3 v1 = p1 - p2;
  const float l0 = glm::length(v0), l1 = glm::length(v1);
  const Vec3 axis = glm::cross(v1, v0);
  const float s = glm::length(axis);
  if (l0 < 1e-12f || l1 < 1e-12f || s < 1e-6f * l0 * l1) return p0 + float(k) * v0;
  const float angle = std::atan2(s, glm::dot(v1, v0));
  const glm::quat turn = glm::angleAxis(angle, axis / s);
  Vec3 p = p0, step = v0;
  for (uint32_t j = 0; j < k; ++j) p += (step = turn * step);
  return p;
}

struct VdrClient::Impl {
  VdrClientOptions options;
  std::string where;
  asio::io_context io;
  std::shared_ptr<net::Connection> connection;
  std::thread get_updates;  // GET-UPDATES: runs the connection

  // Shared between the two procedures.
  mutable std::mutex mutex;
  std::condition_variable arrived_cv;
  std::optional<VdrWelcome> welcome;
  std::deque<Batch> arrived;
  std::vector<net::Clock::time_point> sent_at;  // per request sequence
  std::string failure;
  VdrClientStats stats;
  double batch_ms_smoothed = -1;

  // RENDER's own.
  std::optional<SelectiveMesh> mesh;
  uint32_t next_request = 0, next_apply = 0, span = 1;
  uint32_t applied = kNoBatch;
  uint64_t digest = 0, frame_index = 0;
  Vec3 eye_pp{0.0f}, eye_p{0.0f}, eye_c{0.0f}, aim_pp{0.0f}, aim_p{0.0f}, aim_c{0.0f};
  double frame_ms_smoothed = -1, update_ms = 0;

  void on_message(uint8_t type, std::vector<uint8_t> payload) {
    const auto now = net::Clock::now();
    if (type == uint8_t(VdrMessage::error)) throw Error("the server refused: " + parse_error(payload));
    std::unique_lock lock(mutex);
    stats.bytes_received += payload.size() + net::kFrameHeaderBytes;
    if (!welcome) {
      if (type != uint8_t(VdrMessage::welcome)) throw net::ProtocolError("the server did not welcome this client");
      lock.unlock();
      VdrWelcome w = parse_welcome(payload);
      lock.lock();
      welcome = std::move(w);
    } else {
      if (type != uint8_t(VdrMessage::batch)) throw net::ProtocolError("unexpected message type " + std::to_string(type));
      const uint32_t vsplits = welcome->vsplits;
      lock.unlock();
      Batch b = parse_batch(payload, vsplits);
      lock.lock();
      const uint32_t expected = next_arrival();
      if (b.sequence != expected || b.sequence >= sent_at.size())
        throw net::ProtocolError("batch " + std::to_string(b.sequence) + " where " + std::to_string(expected) + " was due");
      const double ms = std::chrono::duration<double, std::milli>(now - sent_at[b.sequence]).count();
      stats.batch_ms.push_back(ms);
      batch_ms_smoothed = smooth(batch_ms_smoothed, ms);
      ++stats.batches;
      arrived.push_back(std::move(b));
    }
    arrived_cv.notify_all();
  }

  // REQUIRES mutex held.
  uint32_t next_arrival() const { return uint32_t(stats.batches); }

  void on_close(const std::string& reason) {
    const std::lock_guard lock(mutex);
    if (failure.empty()) failure = reason;
    arrived_cv.notify_all();
  }

  [[noreturn]] void failed(const std::string& why) const { throw Error(where + ": " + why); }

  // GET-UPDATES's send: the request goes out on the connection's thread, shaped.
  void send_view(const Vec3& eye, const Vec3& aim, BudgetMode mode) {
    ViewRequest v;
    v.sequence = next_request++;
    v.view = ViewParams{eye, aim, options.alpha, options.tau, mode, options.n, options.server_budget ? options.budget : 0};
    v.applied = applied;
    v.digest = digest;
    {
      const std::lock_guard lock(mutex);
      sent_at.push_back(net::Clock::now());
      stats.bytes_sent += 67;  // 55 bytes and the frame's 12
    }
    asio::post(io, [c = connection, payload = encode_view(v)] { c->send(uint8_t(VdrMessage::view), payload); });
  }

  // Takes the next batch: waits up to the timeout if `wait`, else only if it has arrived.
  std::optional<Batch> take(bool wait) {
    std::unique_lock lock(mutex);
    if (wait)
      arrived_cv.wait_for(lock, std::chrono::duration<double>(options.timeout_s),
                          [&] { return !arrived.empty() || !failure.empty(); });
    if (arrived.empty()) {
      if (!failure.empty()) failed(failure);
      if (wait) failed("no batch within " + std::to_string(int(options.timeout_s)) + " s");
      return std::nullopt;
    }
    Batch b = std::move(arrived.front());
    arrived.pop_front();
    return b;
  }

  // The batch applier: every op in order; the mesh must then hold the server's triangle count.
  uint32_t apply(const Batch& b) {
    const Stopwatch watch;
    try {
      for (const WireOp& op : b.ops) op.split ? mesh->vsplit(vsplit_op(op)) : mesh->ecol(vsplit_op(op));
    } catch (const std::exception& e) {
      broken("batch " + std::to_string(b.sequence) + " does not apply: " + e.what());
    }
    if (mesh->triangle_count() != b.triangles)
      broken("out of step after batch " + std::to_string(b.sequence) + ": " + std::to_string(mesh->triangle_count()) +
             " triangles here, " + std::to_string(b.triangles) + " on the server");
    applied = b.sequence;
    ++next_apply;
    update_ms = watch.ms();  // T_u: the ops; the lockstep digest is a check, not the client's work
    if (options.hello.lockstep) digest = mesh_digest(*mesh);
    return uint32_t(b.ops.size());
  }

  // A mesh out of step with its server stays unusable: every later frame says why.
  [[noreturn]] void broken(const std::string& why) {
    {
      const std::lock_guard lock(mutex);
      failure = why;
      arrived.clear();
    }
    failed(why);
  }

  // Eq. 6.3.1 every kSpanPeriod frames: f = ⌈T_g / (T_u + T_r)⌉.
  void adapt_span() {
    if (!options.adaptive_span || (frame_index % kSpanPeriod != 0 && frame_index != 1) || frame_ms_smoothed <= 0) return;
    double tg;
    {
      const std::lock_guard lock(mutex);
      tg = batch_ms_smoothed;
    }
    if (tg < 0) return;
    span = std::clamp(uint32_t(std::ceil(tg / frame_ms_smoothed)), 1u, options.max_span);
  }

  // Closes the connection and ends GET-UPDATES.
  void shut_down() {
    asio::post(io, [this] {
      connection->close("the client closed");
      io.stop();
    });
    if (get_updates.joinable()) get_updates.join();
  }

  BudgetMode mode_now() const {
    const int64_t alarm = int64_t(options.budget) - 2 * int64_t(options.n) * (options.sequential ? 1 : span);
    return int64_t(mesh->triangle_count()) > alarm ? BudgetMode::kBudget : BudgetMode::kFree;
  }
};

VdrClient::VdrClient(const std::string& host, uint16_t port, VdrClientOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.options = options;
  if (options.n == 0 || options.n > 0xFFFF) fail("N = " + std::to_string(options.n), "ops per frame must be 1-65,535 (the request's 16 bits)");
  m.span = std::clamp(options.span, 1u, options.max_span);
  m.where = host + ":" + std::to_string(port);
  boost::system::error_code ec;
  tcp::resolver resolver(m.io);
  const auto endpoints = resolver.resolve(host, std::to_string(port), ec);
  tcp::socket socket(m.io);
  if (!ec) asio::connect(socket, endpoints, ec);
  if (ec) m.failed("cannot connect (" + ec.message() + "); is `cellwalk serve MODEL.cwvdr` running there?");
  // The welcome carries the base mesh: allow it 256 MiB; a batch is checked against 64 KB.
  m.connection = std::make_shared<net::Connection>(std::move(socket), options.outgoing,
                                                   net::ConnectionLimits{256u << 20, size_t(1) << 20, std::chrono::milliseconds(30000)});
  m.connection->start([&m](uint8_t type, std::vector<uint8_t> payload) { m.on_message(type, std::move(payload)); },
                      [&m](const std::string& reason) { m.on_close(reason); });
  const auto started = net::Clock::now();
  m.connection->send(uint8_t(VdrMessage::hello), encode_hello(options.hello));
  m.get_updates = std::thread([&m] { m.io.run(); });
  std::unique_lock lock(m.mutex);
  m.arrived_cv.wait_for(lock, std::chrono::duration<double>(options.timeout_s), [&] { return m.welcome || !m.failure.empty(); });
  if (!m.welcome) {
    const std::string why = m.failure.empty() ? "no welcome within the timeout" : m.failure;
    lock.unlock();
    m.shut_down();  // the destructor does not run for a constructor that throws
    m.failed(why);
  }
  // The hello's round trip is the first T_g the span rule sees (Eq. 6.3.1 at frame 1).
  m.batch_ms_smoothed = std::chrono::duration<double, std::milli>(net::Clock::now() - started).count();
  const VdrWelcome& w = *m.welcome;
  m.mesh.emplace(w.positions, w.normals, w.indices);
}

VdrClient::~VdrClient() { impl_->shut_down(); }

VdrFrameReport VdrClient::frame(const Vec3& eye, const Vec3& aim) {
  Impl& m = *impl_;
  {
    const std::lock_guard lock(m.mutex);
    if (!m.failure.empty() && m.arrived.empty()) m.failed(m.failure);
  }
  VdrFrameReport r;
  m.eye_pp = m.frame_index <= 1 ? (m.frame_index == 0 ? eye : m.eye_c) : m.eye_p;
  m.aim_pp = m.frame_index <= 1 ? (m.frame_index == 0 ? aim : m.aim_c) : m.aim_p;
  m.eye_p = m.frame_index == 0 ? eye : m.eye_c;
  m.aim_p = m.frame_index == 0 ? aim : m.aim_c;
  m.eye_c = eye;
  m.aim_c = aim;
  m.update_ms = 0;
  if (m.options.sequential) {
    r.mode = m.mode_now();
    m.send_view(eye, aim, r.mode);
    const Stopwatch wait;
    std::optional<Batch> b = m.take(true);
    r.wait_ms = wait.ms();
    r.ops = m.apply(*b);
    r.modified = true;
  } else {
    if (std::optional<Batch> b = m.take(false)) {
      r.ops = m.apply(*b);
      r.modified = true;
    }
    const uint32_t before = m.span;
    m.adapt_span();
    // An unmodified frame sends nothing (§5.3); the first frame sends f requests (Fig. 6.2); a
    // raised span sends the requests for the frames it adds (§6.3).
    if (r.modified || m.frame_index == 0 || m.span > before) {
      r.mode = m.mode_now();
      while (m.next_request - m.next_apply < m.span) {
        const uint32_t k = m.next_request - m.next_apply + 1;
        const Predictor p = m.options.predictor;
        m.send_view(predict_point(p, m.eye_pp, m.eye_p, eye, k), predict_point(p, m.aim_pp, m.aim_p, aim, k), r.mode);
      }
    }
  }
  r.update_ms = m.update_ms;
  r.triangles = m.mesh->triangle_count();
  r.span = m.span;
  r.pending = m.next_request - m.next_apply;
  ++m.frame_index;
  const std::lock_guard lock(m.mutex);
  ++m.stats.frames;
  m.stats.ops += r.ops;
  if (!r.modified) ++m.stats.unmodified;
  m.stats.largest_span = std::max(m.stats.largest_span, m.span);
  return r;
}

void VdrClient::rendered(double ms) {
  Impl& m = *impl_;
  m.frame_ms_smoothed = smooth(m.frame_ms_smoothed, std::max(ms + m.update_ms, 0.5));
}

const SelectiveMesh& VdrClient::mesh() const { return *impl_->mesh; }
const VdrWelcome& VdrClient::welcome() const { return *impl_->welcome; }
uint32_t VdrClient::span() const { return impl_->span; }

VdrClientStats VdrClient::stats() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

}  // namespace cellwalk::vdr
