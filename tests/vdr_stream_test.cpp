// Seed 004 (Zheng) over TCP: the VDR protocol's messages round-trip and refuse damage; a client
// walking the thesis's paths stays in lockstep with the server's shadow mesh under delay, late
// batches and span changes, and under the budget; hostile sessions are dropped alone; many
// clients at once each get what they would get alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>
#include <thread>

#include "cellwalk/core/error.hpp"
#include "cellwalk/net/frame.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/systems/vdr/vdr_client.hpp"
#include "cellwalk/systems/vdr/vdr_paths.hpp"
#include "cellwalk/systems/vdr/vdr_server.hpp"
#include "cellwalk/systems/vdr/vdr_walk.hpp"
#include "test_support.hpp"

namespace cellwalk::vdr {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;

const VdrModel& stream_bunny() {
  static const VdrModel m = [] {
    VdrModel out;
    out.pm = build_progressive_mesh(import_model(test::cgal_mesh("bunny00.off")).objects[0].mesh, {.base_triangles = 200}, "bunny");
    out.dag = build_vsplit_dag(out.pm, DagKind::kMiniRedundant);
    for (const Vec3& p : out.pm.positions) out.bounds.extend(p);
    return out;
  }();
  return m;
}

std::vector<WireOp> stream_ops(const VdrModel& m) {
  Traversal t(m, TraversalKind::kPriority, ErrorUnits::kLength);
  const std::vector<VdrFrame> path = thesis_path(1, m.bounds);
  std::vector<Op> ops;
  t.manage({path[100].eye, path[100].aim, 0.55f, 0.001f, BudgetMode::kFree, 60}, ops);
  t.manage({path[0].eye, path[0].aim, 0.55f, 0.001f, BudgetMode::kFree, 20}, ops);  // some ecols
  std::vector<WireOp> wire;
  for (const Op& op : ops) wire.push_back(wire_op(m.pm, op));
  return wire;
}

// Every message parses back to what was encoded, and a batch is as long as op_wire_bytes says.
TEST(VdrProtocol, MessagesRoundTrip) {
  const VdrModel& m = stream_bunny();
  const Hello h = parse_hello(encode_hello({TraversalKind::kConstant, ErrorUnits::kLength, true}));
  EXPECT_EQ(h.kind, TraversalKind::kConstant);
  EXPECT_EQ(h.units, ErrorUnits::kLength);
  EXPECT_TRUE(h.lockstep);
  ViewRequest v{7, {{1, 2, 3}, {4, 5, 6}, 0.5f, 0.002f, BudgetMode::kBudget, 321, 40000}, 5, 0x1234567890ABCDEFull};
  const std::vector<uint8_t> view = encode_view(v);
  EXPECT_EQ(view.size(), 55u);
  const ViewRequest back = parse_view(view);
  EXPECT_EQ(back.sequence, 7u);
  EXPECT_EQ(back.view.aim, Vec3(4, 5, 6));
  EXPECT_EQ(back.view.mode, BudgetMode::kBudget);
  EXPECT_EQ(back.view.n, 321u);
  EXPECT_EQ(back.view.budget, 40000u);
  EXPECT_EQ(back.digest, v.digest);
  const std::vector<WireOp> ops = stream_ops(m);
  ASSERT_GT(ops.size(), 40u);
  uint32_t expected = kBatchHeaderBytes;
  for (const WireOp& op : ops) expected += op_wire_bytes(m.pm, {op.node, op.split});
  const std::vector<uint8_t> batch = encode_batch(3, 999, ops);
  EXPECT_EQ(batch.size(), expected);
  const Batch b = parse_batch(batch, m.pm.vsplit_count());
  ASSERT_EQ(b.ops.size(), ops.size());
  for (size_t k = 0; k < ops.size(); ++k) {
    EXPECT_EQ(b.ops[k].node, ops[k].node);
    EXPECT_EQ(b.ops[k].split, ops[k].split);
    EXPECT_EQ(b.ops[k].adjusted, ops[k].adjusted);
    if (ops[k].split) {
      EXPECT_EQ(b.ops[k].position, ops[k].position);
      EXPECT_EQ(b.ops[k].v_r, ops[k].v_r);
    }
  }
  const VdrWelcome w = welcome_of(m);
  EXPECT_EQ(encode_welcome(parse_welcome(encode_welcome(w))), encode_welcome(w));
  EXPECT_EQ(parse_error(encode_error("why")), "why");
}

// Every strict prefix of every message and every bad value is a ProtocolError, never a crash.
TEST(VdrProtocol, DamagedMessagesAreRefused) {
  const VdrModel& m = stream_bunny();
  const uint32_t n = m.pm.vsplit_count();
  const std::vector<uint8_t> batch = encode_batch(0, 1, stream_ops(m));
  const std::vector<uint8_t> view = encode_view({0, {{0, 0, 5}, {0, 0, 0}, 0.5f, 0.001f, BudgetMode::kFree, 500}, kNoBatch, 0});
  const std::vector<uint8_t> hello = encode_hello({});
  for (size_t k = 0; k < batch.size(); k += 7) {
    EXPECT_THROW(parse_batch(std::span(batch).first(k), n), net::ProtocolError) << k;
  }
  for (size_t k = 0; k < view.size(); ++k) {
    EXPECT_THROW(parse_view(std::span(view).first(k)), net::ProtocolError) << k;
  }
  for (size_t k = 0; k < hello.size(); ++k) {
    EXPECT_THROW(parse_hello(std::span(hello).first(k)), net::ProtocolError) << k;
  }
  const auto bad_view = [](ViewParams p) { return encode_view({0, p, kNoBatch, 0}); };
  const ViewParams good{{0, 0, 5}, {0, 0, 0}, 0.5f, 0.001f, BudgetMode::kFree, 500};
  ViewParams p = good;
  p.eye.x = std::nanf("");
  EXPECT_THROW(parse_view(bad_view(p)), net::ProtocolError);
  p = good, p.alpha = 4.0f;
  EXPECT_THROW(parse_view(bad_view(p)), net::ProtocolError);
  p = good, p.tau = 0.0f;
  EXPECT_THROW(parse_view(bad_view(p)), net::ProtocolError);
  p = good, p.eye = p.aim;
  EXPECT_THROW(parse_view(bad_view(p)), net::ProtocolError);
  std::vector<uint8_t> mode = bad_view(good);
  mode[36] = 2;  // the mode byte
  EXPECT_THROW(parse_view(mode), net::ProtocolError);
  std::vector<uint8_t> kind = batch;
  kind[kBatchHeaderBytes] = 2;
  EXPECT_THROW(parse_batch(kind, n), net::ProtocolError);
  EXPECT_THROW(parse_batch(batch, 3), net::ProtocolError);  // a node past the model
  std::vector<uint8_t> version = hello;
  version[0] = 9;
  EXPECT_THROW(parse_hello(version), net::ProtocolError);
  EXPECT_NO_THROW(parse_batch(batch, n));
  EXPECT_NO_THROW(parse_view(view));
}

// A server on its own thread, logging.
class VdrServerTest : public ::testing::Test {
 protected:
  void start(VdrServerOptions options) {
    options.log = [this](const std::string& line) {
      const std::lock_guard lock(log_mutex_);
      log_.push_back(line);
    };
    server_ = std::make_unique<VdrServer>(stream_bunny(), options);
    thread_ = std::thread([this] { server_->run(); });
  }
  void TearDown() override {
    if (!server_) return;
    server_->stop();
    thread_.join();
  }
  std::vector<std::string> log() {
    const std::lock_guard lock(log_mutex_);
    return log_;
  }
  std::unique_ptr<VdrServer> server_;
  std::thread thread_;
  std::mutex log_mutex_;
  std::vector<std::string> log_;
};

struct StreamWalk {
  uint64_t digest = 0;
  uint32_t most_triangles = 0;
  VdrClientStats stats;
};

// Walks a thesis path; `frame_ms` paces the frames as a renderer would.
StreamWalk stream_walk(uint16_t port, int path, VdrClientOptions options, double frame_ms, uint32_t frames = 1000) {
  VdrClient client("127.0.0.1", port, options);
  StreamWalk out;
  uint32_t k = 0;
  for (const VdrFrame& f : thesis_path(path, stream_bunny().bounds)) {
    if (k++ == frames) break;
    const VdrFrameReport r = client.frame(f.eye, f.aim);
    out.most_triangles = std::max(out.most_triangles, r.triangles);
    if (frame_ms > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(frame_ms));
    client.rendered(frame_ms);
  }
  out.digest = mesh_digest(client.mesh());
  out.stats = client.stats();
  return out;
}

// Lockstep (the server checks the client's digest of its mesh against its shadow after every
// batch) along both paths, with 15 ms each way, frames faster than the round trip (late batches,
// unmodified frames) and the span adapting to it; the mesh stays under B whether the server holds
// the budget (path 1) or the client's alarm level does (path 2).
TEST_F(VdrServerTest, ClientStaysInLockstepUnderDelayLateBatchesAndSpanChanges) {
  VdrServerOptions so;
  so.link.latency_ms = 15;
  start(so);
  for (int path : {1, 2}) {
    SCOPED_TRACE("path " + std::to_string(path));
    VdrClientOptions o;
    o.outgoing.latency_ms = 15;
    o.hello = {TraversalKind::kPriority, ErrorUnits::kLength, true};
    o.budget = 12000;
    o.n = 300;
    o.adaptive_span = true;
    o.span = 1;
    o.server_budget = path == 1;
    const StreamWalk r = stream_walk(server_->port(), path, o, 4.0);
    EXPECT_LE(r.most_triangles, o.budget);
    EXPECT_GT(r.most_triangles, o.budget / 2);
    EXPECT_GE(r.stats.largest_span, 4u);  // the span rose from 1 with T_g ≈ 30 ms over 4 ms frames
    EXPECT_GT(r.stats.unmodified, 0u);
    EXPECT_GT(r.stats.ops, 5000u);
  }
  EXPECT_EQ(server_->stats().sessions_dropped, 0u);
  EXPECT_GT(server_->stats().batches, 300u);
}

// Beyond the thesis: start-up, the gradual fill and catch-up after jumps (path 1 jumps twice)
// keep the lockstep; start-up ends with the mesh of the primed sequential reference, and each
// jump sends its catch-up requests.
TEST_F(VdrServerTest, PrimedClientWithCatchUpStaysInLockstepAndStartsFromTheReference) {
  VdrServerOptions so;
  so.link.latency_ms = 10;
  start(so);
  VdrClientOptions o;
  o.outgoing.latency_ms = 10;
  o.hello = {TraversalKind::kPriority, ErrorUnits::kLength, true};
  o.budget = 12000;
  o.n = 300;
  o.adaptive_span = true;
  o.predictor = Predictor::kTurn;
  o.gradual_fill = true;
  o.jump_catch_up = 6;
  const std::vector<VdrFrame> path = thesis_path(1, stream_bunny().bounds);
  VdrClient client("127.0.0.1", server_->port(), o);
  const VdrPrimeReport prime = client.prime(path[0].eye, path[0].aim);
  EXPECT_TRUE(prime.converged);
  EXPECT_GT(prime.batches, 2u);
  EXPECT_EQ(prime.triangles, client.mesh().triangle_count());
  ReferenceWalk reference(stream_bunny(), o.hello, o);
  EXPECT_TRUE(reference.prime(path[0].eye, path[0].aim));
  EXPECT_EQ(triangle_accuracy(client.mesh(), reference.step(path[0].eye, path[0].aim)), 1.0);
  EXPECT_THROW(client.prime(path[0].eye, path[0].aim), Error) << "a second start-up is refused";
  uint32_t most_ops = 0;
  for (const VdrFrame& f : path) {
    const VdrFrameReport r = client.frame(f.eye, f.aim);
    most_ops = std::max(most_ops, r.ops);
    std::this_thread::sleep_for(std::chrono::milliseconds(4));
    client.rendered(4);
  }
  // Catch-up: 6 requests after each of the two jumps, however late the batches come (a count of
  // all batches received is not: a frame sends no regular request while f are pending).
  const VdrClientStats stats = client.stats();
  EXPECT_EQ(stats.catch_up_requests, 2u * o.jump_catch_up);
  EXPECT_GT(stats.requests, stats.catch_up_requests + prime.batches);
  EXPECT_GT(most_ops, o.n) << "a frame applied a batch and its catch-up batches";
  EXPECT_EQ(server_->stats().sessions_dropped, 0u);
}

// Catch-up as large as start-up is capped: with N = 10, start-up takes hundreds of batches, and
// that many catch-up requests after a jump would leave a lockstep server holding more than 256
// unconfirmed batches (it would drop the session).
TEST_F(VdrServerTest, CatchUpAsLargeAsStartUpIsCapped) {
  start({});
  VdrClientOptions o;
  o.hello = {TraversalKind::kPriority, ErrorUnits::kLength, true};
  o.n = 10;
  o.span = 2;
  o.predictor = Predictor::kTurn;
  o.gradual_fill = true;
  o.jump_catch_up = 1;
  o.catch_up_as_start_up = true;
  const std::vector<VdrFrame> path = thesis_path(1, stream_bunny().bounds);
  VdrClient client("127.0.0.1", server_->port(), o);
  const VdrPrimeReport prime = client.prime(path[0].eye, path[0].aim);
  ASSERT_GT(prime.batches, 256u) << "start-up must take more batches than a lockstep server holds";
  uint32_t most_pending = 0;
  for (size_t i = 0; i < 140; ++i) {  // past the jump at frame 110; the catch-up goes at 111
    const VdrFrameReport r = client.frame(path[i].eye, path[i].aim);
    most_pending = std::max(most_pending, r.pending);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  EXPECT_GT(most_pending, o.span + kMaxJumpCatchUp / 2) << "no catch-up after the jump";
  EXPECT_LE(most_pending, o.span + kMaxJumpCatchUp + 1);
  EXPECT_EQ(server_->stats().sessions_dropped, 0u) << log().back();
}

// The server's lockstep check can fail: a client whose digest is not the shadow's is dropped.
TEST_F(VdrServerTest, ADigestThatDiffersFromTheShadowDropsTheSession) {
  start({});
  asio::io_context io;
  tcp::socket s(io);
  s.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server_->port()));
  const auto send = [&](VdrMessage type, const std::vector<uint8_t>& payload) {
    asio::write(s, asio::buffer(net::make_frame(uint8_t(type), payload)));
  };
  const auto receive = [&] {
    std::array<uint8_t, net::kFrameHeaderBytes> h{};
    asio::read(s, asio::buffer(h));
    const net::FrameHeader header = net::parse_frame_header(h, 1u << 30);
    std::vector<uint8_t> payload(header.length);
    asio::read(s, asio::buffer(payload));
    return std::make_pair(VdrMessage(header.type), payload);
  };
  send(VdrMessage::hello, encode_hello({TraversalKind::kPriority, ErrorUnits::kLength, true}));
  const VdrWelcome w = parse_welcome(receive().second);
  SelectiveMesh mesh(w.positions, w.normals, w.indices);
  const VdrFrame f = thesis_path(1, w.bounds)[100];
  send(VdrMessage::view, encode_view({0, {f.eye, f.aim, 0.55f, 0.001f, BudgetMode::kFree, 100}, kNoBatch, 0}));
  const Batch b = parse_batch(receive().second, w.vsplits);
  ASSERT_GT(b.ops.size(), 10u);
  for (const WireOp& op : b.ops) op.split ? mesh.vsplit(vsplit_op(op)) : mesh.ecol(vsplit_op(op));
  // The right digest is taken; then the same batch reported with one op left out is not.
  send(VdrMessage::view, encode_view({1, {f.eye, f.aim, 0.55f, 0.001f, BudgetMode::kFree, 100}, 0, mesh_digest(mesh)}));
  EXPECT_EQ(receive().first, VdrMessage::batch);
  SelectiveMesh short_one(w.positions, w.normals, w.indices);
  for (size_t k = 0; k + 1 < b.ops.size(); ++k) short_one.vsplit(vsplit_op(b.ops[k]));
  send(VdrMessage::view, encode_view({2, {f.eye, f.aim, 0.55f, 0.001f, BudgetMode::kFree, 100}, 0, mesh_digest(short_one)}));
  const auto [type, payload] = receive();
  ASSERT_EQ(type, VdrMessage::error);
  EXPECT_NE(parse_error(payload).find("lockstep lost"), std::string::npos) << parse_error(payload);
  std::vector<uint8_t> sink(256);
  boost::system::error_code ec;
  while (!ec) s.read_some(asio::buffer(sink), ec);  // the server closes the session
  for (int k = 0; k < 200 && server_->stats().sessions_dropped == 0; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(server_->stats().sessions_dropped, 1u);
}

// Hostile peers — garbage, a 4 GiB length, a truncated view, a view before hello, a request out
// of sequence, a header then silence, a disconnect mid-message — are each dropped with a logged
// reason while clients beside them walk on: each good client's mesh is the one it gets alone.
TEST_F(VdrServerTest, HostileSessionsAreDroppedAloneAndOthersAreServedAsIfAlone) {
  VdrServerOptions so;
  so.limits.stall = std::chrono::milliseconds(300);
  start(so);
  VdrClientOptions o;
  o.hello = {TraversalKind::kLinear, ErrorUnits::kLength, true};
  o.budget = 15000;
  o.sequential = true;  // deterministic: each batch answers the true view
  const uint64_t alone1 = stream_walk(server_->port(), 1, o, 0, 120).digest, alone2 = stream_walk(server_->port(), 2, o, 0, 120).digest;
  ASSERT_NE(alone1, alone2);

  const std::vector<uint8_t> hello = net::make_frame(uint8_t(VdrMessage::hello), encode_hello({}));
  const auto after_hello = [&](const std::vector<uint8_t>& more) {
    std::vector<uint8_t> out = hello;
    out.insert(out.end(), more.begin(), more.end());
    return out;
  };
  const ViewRequest view{0, {{0, 0, 1}, {0, 0, 0}, 0.5f, 0.001f, BudgetMode::kFree, 500}, kNoBatch, 0};
  std::vector<uint8_t> truncated = encode_view(view);
  truncated.resize(20);
  ViewRequest late = view;
  late.sequence = 5;
  std::vector<uint8_t> huge = hello;
  huge[8] = huge[9] = huge[10] = huge[11] = 0xFF;
  std::vector<uint8_t> stalled = hello;
  stalled.resize(net::kFrameHeaderBytes + 2);
  const std::vector<std::pair<std::string, std::vector<uint8_t>>> cases = {
      {"bad magic", std::vector<uint8_t>(40, 'z')},
      {"more than the", huge},
      {"malformed view", after_hello(net::make_frame(uint8_t(VdrMessage::view), truncated))},
      {"first message must be hello", net::make_frame(uint8_t(VdrMessage::view), encode_view(view))},
      {"where 0 was due", after_hello(net::make_frame(uint8_t(VdrMessage::view), encode_view(late)))},
      {"stalled", stalled}};
  asio::io_context io;
  std::vector<tcp::socket> sockets;
  for (const auto& c : cases) {
    sockets.emplace_back(io);
    sockets.back().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server_->port()));
    asio::write(sockets.back(), asio::buffer(c.second));
  }
  {  // a disconnect in the middle of a message
    tcp::socket s(io);
    s.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server_->port()));
    std::vector<uint8_t> half = after_hello(net::make_frame(uint8_t(VdrMessage::view), encode_view(view)));
    half.resize(half.size() - 10);
    asio::write(s, asio::buffer(half));
  }
  uint64_t digests[4] = {};
  std::vector<std::thread> good;
  for (int k = 0; k < 4; ++k) good.emplace_back([&, k] { digests[k] = stream_walk(server_->port(), 1 + k % 2, o, 0, 120).digest; });
  for (tcp::socket& s : sockets) {
    std::vector<uint8_t> sink(1 << 16);
    boost::system::error_code ec;
    while (!ec) s.read_some(asio::buffer(sink), ec);
  }
  for (std::thread& t : good) t.join();
  for (int k = 0; k < 4; ++k) EXPECT_EQ(digests[k], k % 2 == 0 ? alone1 : alone2) << "client " << k;
  for (int k = 0; k < 200 && server_->stats().sessions_dropped < cases.size() + 1; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const std::vector<std::string> lines = log();
  for (const auto& c : cases) {
    const std::string& reason = c.first;
    EXPECT_TRUE(std::any_of(lines.begin(), lines.end(), [&](const std::string& l) {
      return l.find("dropped") != std::string::npos && l.find(reason) != std::string::npos;
    })) << reason;
  }
  EXPECT_TRUE(std::any_of(lines.begin(), lines.end(), [](const std::string& l) { return l.find("mid-message") != std::string::npos; }));
  EXPECT_EQ(server_->stats().sessions_dropped, cases.size() + 1);
  EXPECT_GT(server_->stats().peak_one_session_bytes, 0u);
}

// A client told by the server why it was dropped says so; no server: one line saying what to run.
TEST_F(VdrServerTest, ClientErrorsNameTheCause) {
  start({});
  const uint16_t port = server_->port();
  server_->stop();
  thread_.join();
  server_.reset();
  try {
    VdrClient c("127.0.0.1", port, {});
    FAIL() << "connected to a stopped server";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cellwalk serve"), std::string::npos) << e.what();
  }
}

// Sessions past max_sessions are refused with a reason the client names; a session that falls
// silent is dropped after the idle time, with the reason logged, and its place is free again.
TEST_F(VdrServerTest, TooManySessionsAreRefusedAndSilentOnesDropped) {
  VdrServerOptions so;
  so.max_sessions = 2;
  so.idle = std::chrono::milliseconds(400);
  start(so);
  VdrClientOptions o;
  o.timeout_s = 5;
  VdrClient first("127.0.0.1", server_->port(), o), second("127.0.0.1", server_->port(), o);
  try {
    VdrClient third("127.0.0.1", server_->port(), o);
    ADD_FAILURE() << "a third session was welcomed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the server is full (2 sessions)"), std::string::npos) << e.what();
  }
  EXPECT_EQ(server_->stats().sessions_refused, 1u);
  // Both fall silent: each is dropped, and its next frame says why.
  std::this_thread::sleep_for(std::chrono::milliseconds(900));
  EXPECT_EQ(server_->stats().sessions_dropped, 2u);
  try {
    first.frame({0, 0, 1}, {0, 0, 0});
    first.frame({0, 0, 1}, {0, 0, 0});
    ADD_FAILURE() << "a dropped session went on";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("sent nothing for 400 ms"), std::string::npos) << e.what();
  }
  const std::vector<std::string> lines = log();
  EXPECT_EQ(std::count_if(lines.begin(), lines.end(), [](const std::string& l) { return l.find("dropped: sent nothing") != std::string::npos; }), 2);
  // A client that keeps drawing is never idle.
  o.sequential = true;
  const StreamWalk w = stream_walk(server_->port(), 1, o, 5.0, 120);
  EXPECT_GT(w.stats.ops, 100u);
  EXPECT_EQ(server_->stats().sessions_dropped, 2u);
}

// A server that sends a batch past 64 KB (after a welcome of any size) is refused by the client
// without reading it, naming the size.
TEST(VdrClientLimits, ABatchPastTheLimitIsRefused) {
  // The model is built first: under the sanitizers that takes seconds, which the client's wait
  // for its welcome must not include.
  const std::vector<uint8_t> welcome = net::make_frame(uint8_t(VdrMessage::welcome), encode_welcome(welcome_of(stream_bunny())));
  asio::io_context io;
  tcp::acceptor acceptor(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  // Never throws, and joins whatever the test does: a failed client leaves it reading an EOF.
  std::jthread hostile([&] {
    boost::system::error_code ec;
    tcp::socket s(io);
    acceptor.accept(s, ec);
    std::array<uint8_t, net::kFrameHeaderBytes + 8> hello{};
    if (!ec) asio::read(s, asio::buffer(hello), ec);
    if (!ec) asio::write(s, asio::buffer(welcome), ec);
    if (!ec) asio::write(s, asio::buffer(net::make_frame(uint8_t(VdrMessage::batch), std::vector<uint8_t>(kMaxBatchBytes + 1, 0))), ec);
    std::vector<uint8_t> sink(256);
    while (!ec) s.read_some(asio::buffer(sink), ec);  // until the client closes
  });
  VdrClient client("127.0.0.1", acceptor.local_endpoint().port(), VdrClientOptions{});
  std::string why;
  for (int k = 0; k < 500 && why.empty(); ++k) {
    try {
      client.frame({0, 0, 1}, {0, 0, 0});
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    } catch (const Error& e) {
      why = e.what();
    }
  }
  EXPECT_NE(why.find(std::to_string(kMaxBatchBytes + 1)), std::string::npos) << why;
}

// The coordinated turn with tangential acceleration follows a point accelerating round a circle
// far better than dead reckoning; a jump is not extrapolated, and the step after one is.
TEST(VdrPrediction, TurnFollowsAcceleratingTurnsAndDoesNotExtrapolateJumps) {
  const auto orbit = [](float t) {
    const float angle = 0.02f * t + 0.002f * t * t;
    return Vec3(5 * std::cos(angle), 1.0f, 5 * std::sin(angle));
  };
  for (uint32_t k : {1u, 6u, 12u}) {
    SCOPED_TRACE("k = " + std::to_string(k));
    const Vec3 truth = orbit(float(20 + k));
    const float turn = glm::length(predict_point(Predictor::kTurn, orbit(18), orbit(19), orbit(20), k) - truth);
    const float linear = glm::length(predict_point(Predictor::kLinear, orbit(18), orbit(19), orbit(20), k) - truth);
    EXPECT_LT(turn, 0.1f * linear);
    EXPECT_LT(turn, 0.02f * glm::length(orbit(20) - truth));
  }
  const Vec3 a(0.0f), b(0.1f, 0, 0), landed(0, 5, 0), next(0, 5.1f, 0);
  EXPECT_EQ(predict_point(Predictor::kTurn, a, b, landed, 10), landed);               // a jump: stay where it landed
  EXPECT_EQ(predict_point(Predictor::kTurn, b, landed, next, 10), next + 10.0f * (next - landed));  // then its motion
  EXPECT_EQ(predict_point(Predictor::kNone, a, b, landed, 10), landed);
  // A step 8 times the one before but shorter than least_jump is motion (starting to move).
  const Vec3 slow(0.1f, 0, 0), fast(1.2f, 0, 0);
  EXPECT_EQ(predict_point(Predictor::kTurn, a, slow, fast, 2, 0.0f), fast);
  // Not a jump: steps of 1.1 + 1.0 and 1.1 + 2.0 (the length grew by 1.0 a step).
  EXPECT_NEAR(predict_point(Predictor::kTurn, a, slow, fast, 2, 5.0f).x, 1.2f + 2.1f + 3.1f, 1e-4f);
}

// The commands: connect walks a served model and measures it against the model file; serve
// serves a .cwvdr for a while; bad addresses and mismatched models are one line each.
TEST_F(VdrServerTest, ConnectAndServeCommands) {
  start({});
  const test::TempDir dir;
  const VdrModel& m = stream_bunny();
  write_vdr_file(dir.file("bunny.cwvdr"), m.pm, m.dag);
  const std::string address = "127.0.0.1:" + std::to_string(server_->port());
  const test::CommandResult r = test::run_cellwalk("connect " + address + " --model " + dir.file("bunny.cwvdr") +
                                                   " --frame-ms 0 --sequential --lockstep --budget 15000 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"accuracy\": 1.0"), std::string::npos) << r.output;  // sequential = the reference
  EXPECT_NE(r.output.find("\"frames\": 180"), std::string::npos) << r.output;
  for (const std::string& bad : std::vector<std::string>{"connect nowhere --frame-ms 0", "connect 127.0.0.1:0 --frame-ms 0",
                                 "connect " + address + " --span 0", "connect " + address + " --predictor magic"}) {
    const test::CommandResult b = test::run_cellwalk(bad);
    EXPECT_NE(b.exit_code, 0) << bad;
    EXPECT_EQ(std::count(b.output.begin(), b.output.end(), '\n'), 1) << bad << ": " << b.output;
  }
  const test::CommandResult s = test::run_cellwalk("serve " + dir.file("bunny.cwvdr") + " --seconds 0.5 --json --quiet");
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_NE(s.output.find("\"sessions\": 0"), std::string::npos) << s.output;
  EXPECT_EQ(server_->stats().sessions_dropped, 0u);
}

}  // namespace
}  // namespace cellwalk::vdr
