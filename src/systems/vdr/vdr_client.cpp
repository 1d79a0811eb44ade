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
// A step this many times its predecessor is a cut in the path (a teleport, a scripted jump),
// not motion: the turn predictor does not extrapolate it (docs/vdr.md "Prediction"). The client
// also asks the step to be this share of the model's diagonal, so that starting to move or to
// turn is not a jump.
constexpr float kJumpRatio = 8.0f;
constexpr float kJumpShare = 0.05f;

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

Vec3 predict_point(Predictor predictor, const Vec3& p2, const Vec3& p1, const Vec3& p0, uint32_t k, float least_jump) {
  const Vec3 v0 = p0 - p1;
  if (predictor == Predictor::kNone) return p0;
  if (predictor == Predictor::kLinear) return p0 + float(k) * v0;
  // The coordinated turn with constant tangential acceleration: each step j is turned from the
  // one before by the curvature the last two steps show, over its length; the lengths change by
  // l0 − l1 a step (never below zero).
  const Vec3 v1 = p1 - p2;
  const float l0 = glm::length(v0), l1 = glm::length(v1);
  if (l1 > 0 && l0 > kJumpRatio * l1 && l0 > least_jump) return p0;  // v0 is a jump: where it landed is the best guess
  if (l0 > 0 && l1 > kJumpRatio * l0 && l1 > least_jump) return p0 + float(k) * v0;  // v1 was a jump: v0 is the motion
  if (l0 < 1e-12f || l1 < 1e-12f) return p0 + float(k) * v0;
  const Vec3 cross = glm::cross(v1, v0);
  const float s = glm::length(cross);
  const Vec3 axis = s < 1e-6f * l0 * l1 ? Vec3(0.0f) : cross / s;
  const float curvature = std::atan2(s, glm::dot(v1, v0)) / (0.5f * (l0 + l1));  // radians per unit length
  Vec3 p = p0, direction = v0 / l0;
  float length = l0;
  for (uint32_t j = 0; j < k; ++j) {
    const float next = std::max(0.0f, length + (l0 - l1));
    if (s >= 1e-6f * l0 * l1) direction = glm::angleAxis(curvature * 0.5f * (length + next), axis) * direction;
    p += next * direction;
    length = next;
  }
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
  std::vector<bool> catch_up;  // per request sequence: sent after a jump, applied with its predecessor
  uint32_t catch_up_pending = 0;
  bool jumped_last_frame = false;
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
      connection->set_max_payload(kMaxBatchBytes);  // this runs on the connection's thread
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
  void send_view(const Vec3& eye, const Vec3& aim, BudgetMode mode, bool is_catch_up = false) {
    catch_up.push_back(is_catch_up);
    catch_up_pending += is_catch_up;
    ViewRequest v;
    v.sequence = next_request++;
    v.view = ViewParams{eye, aim, options.alpha, options.tau, mode, options.n, options.server_budget ? options.budget : 0};
    v.applied = applied;
    v.digest = digest;
    {
      const std::lock_guard lock(mutex);
      sent_at.push_back(net::Clock::now());
      stats.bytes_sent += 67;  // 55 bytes and the frame's 12
      ++stats.requests;
      stats.catch_up_requests += is_catch_up;
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
    if (b.sequence < catch_up.size() && catch_up[b.sequence]) --catch_up_pending;
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

  // Applies the arrived catch-up batches that follow the batch just applied. Returns their ops.
  uint32_t apply_catch_up() {
    uint32_t ops = 0;
    while (next_apply < catch_up.size() && catch_up[next_apply]) {
      const std::optional<Batch> b = take(false);
      if (!b) break;
      ops += apply(*b);
    }
    return ops;
  }

  // The shortest step that can be a jump: kJumpShare of the model's diagonal.
  float least_jump() const { return kJumpShare * glm::length(welcome->bounds.size()); }

  // This frame's step of the eye or the aim is a jump (kJumpRatio times the step before, and
  // at least least_jump()).
  bool jumped() const {
    const auto jump = [this](const Vec3& p2, const Vec3& p1, const Vec3& p0) {
      const float l0 = glm::length(p0 - p1), l1 = glm::length(p1 - p2);
      return l1 > 0 && l0 > kJumpRatio * l1 && l0 > least_jump();
    };
    return frame_index >= 2 && (jump(eye_pp, eye_p, eye_c) || jump(aim_pp, aim_p, aim_c));
  }

  // FREE below the alarm level L = B − 2 N f for f requests in flight (§6.3), else BUDGET.
  BudgetMode mode_now(uint32_t in_flight) const {
    const int64_t alarm = int64_t(options.budget) - 2 * int64_t(options.n) * in_flight;
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
  // The welcome carries the base mesh: allow it 256 MiB; every later message is a batch of at
  // most 64 KB (or a short error), and the limit drops to that once the welcome is in.
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
    r.mode = m.mode_now(1);
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
      r.ops += m.apply_catch_up();
    }
    const uint32_t before = m.span;
    m.adapt_span();
    r.mode = m.mode_now(m.span + m.catch_up_pending + (m.jumped_last_frame ? m.options.jump_catch_up : 0));
    const auto pending = [&] { return m.next_request - m.next_apply - m.catch_up_pending; };
    uint32_t k_sent = pending() + 1;
    const Predictor p = m.options.predictor;
    const auto send = [&](uint32_t k, bool is_catch_up) {
      k_sent = k;
      const float least = m.least_jump();
      m.send_view(predict_point(p, m.eye_pp, m.eye_p, eye, k, least), predict_point(p, m.aim_pp, m.aim_p, aim, k, least), r.mode,
                  is_catch_up);
    };
    if (m.options.gradual_fill) {
      // One request a frame while fewer than f are pending, each for the frame it will be
      // applied at: after those pending, and no sooner than f frames from now.
      if (pending() < m.span) send(std::max(pending() + 1, m.span), false);
    } else if (r.modified || m.frame_index == 0 || m.span > before) {
      // An unmodified frame sends nothing (§5.3); the first frame sends f requests (Fig. 6.2); a
      // raised span sends the requests for the frames it adds (§6.3).
      while (pending() < m.span) send(pending() + 1, false);
    }
    // The frame after a jump (when the motion after it is known): requests for the view the
    // regular one predicts, applied with it, so the mesh catches up one round trip after the
    // jump, not N ops a frame later still.
    if (m.jumped_last_frame && m.next_request > 0)
      for (uint32_t i = 0; i < m.options.jump_catch_up; ++i) send(k_sent, true);
    m.jumped_last_frame = m.jumped();
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

void VdrClient::set_alpha(float alpha) { impl_->options.alpha = alpha; }

void VdrClient::rendered(double ms) {
  Impl& m = *impl_;
  m.frame_ms_smoothed = smooth(m.frame_ms_smoothed, std::max(ms + m.update_ms, 0.5));
}

VdrPrimeReport VdrClient::prime(const Vec3& eye, const Vec3& aim) {
  Impl& m = *impl_;
  if (m.frame_index != 0 || m.next_request != 0) m.failed("prime() must come before the first frame");
  const Stopwatch watch;
  VdrPrimeReport r;
  // Requests for the one view, kPrimeWindow in flight: the server answers each from the cut its
  // predecessors left, so the batches refine on without waiting a round trip each.
  while (!r.converged || m.next_apply < m.next_request) {
    while (!r.converged && r.batches + (m.next_request - m.next_apply) < m.options.prime_batches &&
           m.next_request - m.next_apply < kPrimeWindow)
      m.send_view(eye, aim, m.mode_now(kPrimeWindow));
    if (m.next_apply == m.next_request) break;  // the limit reached before convergence
    const std::optional<Batch> b = m.take(true);
    m.apply(*b);
    ++r.batches;
    r.converged = r.converged || b->ops.empty();
  }
  r.ms = watch.ms();
  r.triangles = m.mesh->triangle_count();
  if (m.options.jump_catch_up > 0 && m.options.catch_up_as_start_up)
    m.options.jump_catch_up = std::max(m.options.jump_catch_up, std::min(r.batches, kMaxJumpCatchUp));
  // The window's later batches queued behind the earlier: the fastest is the round trip the
  // span rule should start from.
  const std::lock_guard lock(m.mutex);
  if (!m.stats.batch_ms.empty()) m.batch_ms_smoothed = *std::min_element(m.stats.batch_ms.begin(), m.stats.batch_ms.end());
  return r;
}

const SelectiveMesh& VdrClient::mesh() const { return *impl_->mesh; }
const VdrWelcome& VdrClient::welcome() const { return *impl_->welcome; }
uint32_t VdrClient::span() const { return impl_->span; }

VdrClientStats VdrClient::stats() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

}  // namespace cellwalk::vdr
