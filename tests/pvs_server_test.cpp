// The PVS streaming server and client over real loopback sockets (seed 004, §7.3–7.4 over TCP):
// fetches against the stored sets and the world's bytes, the server's mirror of what a client
// holds, delays that are real, and hostile sessions dropped alone.
#include <gtest/gtest.h>

// Boost 1.74's Asio uses std::exchange without including <utility>.
#include <utility>
#include <boost/asio.hpp>
#include <chrono>
#include <set>
#include <thread>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/net/frame.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/pvs_stream/pvs_server.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using namespace pvs_stream;
namespace asio = boost::asio;
using asio::ip::tcp;

class PvsServerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    inputs_ = new test::SharedInputs(
        "pvs-server-city", {"generate city --objects 40 --seed 3 -o {dir}/city.cwscene", "build {dir}/city.cwscene -o {dir}/city.cww",
                            "pvs {dir}/city.cww --engine conservative --cells grid:30"});
  }
  static void TearDownTestSuite() { delete inputs_; }

  void start(PvsServerOptions options = {}) {
    world_ = std::make_unique<World>(inputs_->file("city.cww"));
    options.log = [this](const std::string& line) {
      const std::lock_guard lock(log_mutex_);
      log_.push_back(line);
    };
    server_ = std::make_unique<PvsServer>(*world_, options);
    thread_ = std::thread([this] { server_->run(); });
  }
  void TearDown() override {
    if (server_) server_->stop();
    if (thread_.joinable()) thread_.join();
  }
  std::vector<std::string> log() {
    const std::lock_guard lock(log_mutex_);
    return log_;
  }
  // The computed cells, in id order.
  std::vector<uint32_t> computed_cells() const {
    std::vector<uint32_t> cells;
    const PvsClient client("127.0.0.1", server_->port());
    for (uint32_t c : client.welcome().cells)
      if (c != kNoCell) cells.push_back(c);
    std::sort(cells.begin(), cells.end());
    return cells;
  }

  static inline test::SharedInputs* inputs_ = nullptr;
  std::unique_ptr<World> world_;
  std::unique_ptr<PvsServer> server_;
  std::thread thread_;
  std::mutex log_mutex_;
  std::vector<std::string> log_;
};

// Rows are the stored sets; objects are the union's less what the client holds (its drops
// named), byte for byte the world file's levels; the grid places every computed cell once.
TEST_F(PvsServerTest, FetchesSendTheRowsAndOnlyTheObjectsTheClientLacks) {
  start();
  PvsClient client("127.0.0.1", server_->port());
  const Welcome& w = client.welcome();
  EXPECT_EQ(w.objects, world_->object_count());
  const visibility::StoredPvs pvs(*world_);
  EXPECT_EQ(w.cell_count, pvs.partition().cell_count());
  std::vector<uint32_t> cells = computed_cells();
  ASSERT_GE(cells.size(), 4u);
  for (uint32_t c : cells) {  // each cell's slot holds its own box's corner
    const auto at = std::find(w.cells.begin(), w.cells.end(), c) - w.cells.begin();
    const Aabb& box = pvs.partition().cell(c).box;
    EXPECT_NEAR(w.origin_x + double(at % w.cols) * w.cell_size, box.min.x, 1e-3);
    EXPECT_NEAR(w.origin_z + double(at / w.cols) * w.cell_size, box.min.z, 1e-3);
  }
  std::set<uint32_t> held;
  uint32_t sequence = 0;
  Random rng(5);
  for (int round = 0; round < 6; ++round) {
    FetchRequest f;
    f.sequence = ++sequence;
    f.level = uint32_t(round % 3);
    for (int k = 0; k < 3; ++k) f.cells.push_back(cells[rng.integer(0, int64_t(cells.size()) - 1)]);
    for (uint32_t id : held)
      if (rng.chance(0.3)) f.dropped.push_back(id);
    for (uint32_t id : f.dropped) held.erase(id);
    const PvsClient::Reply reply = client.fetch(f);
    std::set<uint32_t> wanted;
    ASSERT_EQ(reply.rows.rows.size(), f.cells.size());
    for (size_t i = 0; i < f.cells.size(); ++i) {
      EXPECT_EQ(reply.rows.rows[i].first, f.cells[i]);
      const auto set = pvs.set(f.cells[i]);
      const std::vector<uint32_t> expected = set ? std::vector<uint32_t>(set->objects.begin(), set->objects.end()) : std::vector<uint32_t>{};
      EXPECT_EQ(reply.rows.rows[i].second, expected);
      wanted.insert(expected.begin(), expected.end());
    }
    std::set<uint32_t> sent;
    for (const ObjectReply& o : reply.objects) {
      EXPECT_TRUE(sent.insert(o.id).second) << "object " << o.id << " sent twice";
      EXPECT_EQ(o.level, std::min(f.level, world_->object(o.id).lod_count - 1));
      EXPECT_EQ(o.bytes, world_->read_level(o.id, o.level)) << "object " << o.id;
    }
    std::set<uint32_t> expected_sent;
    for (uint32_t id : wanted)
      if (!held.count(id)) expected_sent.insert(id);
    EXPECT_EQ(sent, expected_sent) << "round " << round;
    held.insert(sent.begin(), sent.end());
  }
  EXPECT_EQ(server_->stats().fetches, 6u);
}

// Delays are real: a fetch waits for the client's and the server's one-way delays.
TEST_F(PvsServerTest, InjectedLatencyDelaysEveryRoundTrip) {
  PvsServerOptions options;
  options.link.latency_ms = 60;
  start(options);
  PvsClient fast("127.0.0.1", server_->port()), slow("127.0.0.1", server_->port(), {40, 0});
  const uint32_t cell = computed_cells().front();
  const auto time_fetch = [&](PvsClient& c, uint32_t sequence) {
    const auto t0 = std::chrono::steady_clock::now();
    c.fetch({sequence, 0, {cell}, {}});
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  };
  EXPECT_GE(time_fetch(fast, 1), 60.0);
  EXPECT_GE(time_fetch(slow, 1), 100.0);
  EXPECT_LT(time_fetch(fast, 2), 1000.0);
}

// Raw bytes from a hostile peer: each such session is dropped with a logged reason, and a client
// beside it goes on being served.
TEST_F(PvsServerTest, HostileSessionsAreDroppedAloneWithAReason) {
  PvsServerOptions options;
  options.limits.stall = std::chrono::milliseconds(300);
  start(options);
  PvsClient good("127.0.0.1", server_->port());
  const uint32_t cell = computed_cells().front();
  asio::io_context io;
  const auto raw = [&](const std::vector<uint8_t>& bytes) {
    tcp::socket s(io);
    s.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server_->port()));
    asio::write(s, asio::buffer(bytes));
    return s;
  };
  const std::vector<uint8_t> hello = net::make_frame(uint8_t(PvsMessage::hello), encode_hello());
  std::vector<uint8_t> bad_fetch = hello;
  const std::vector<uint8_t> fetch = net::make_frame(uint8_t(PvsMessage::fetch), encode_fetch({1, 0, {999999}, {}}));
  bad_fetch.insert(bad_fetch.end(), fetch.begin(), fetch.end());
  std::vector<uint8_t> huge = net::make_frame(uint8_t(PvsMessage::hello), encode_hello());
  huge[8] = huge[9] = huge[10] = huge[11] = 0xFF;  // a 4 GiB message
  std::vector<uint8_t> stalled = net::make_frame(uint8_t(PvsMessage::hello), encode_hello());
  stalled.resize(net::kFrameHeaderBytes + 1);  // the header, then one byte of four
  const std::vector<std::pair<std::string, std::vector<uint8_t>>> cases = {
      {"bad magic", std::vector<uint8_t>(32, 'x')},
      {"more than the", huge},
      {"is not below", bad_fetch},
      {"stalled", stalled},
      {"first message must be hello", net::make_frame(uint8_t(PvsMessage::fetch), encode_fetch({1, 0, {cell}, {}}))}};
  std::vector<tcp::socket> sockets;
  for (const auto& [reason, bytes] : cases) sockets.push_back(raw(bytes));
  for (tcp::socket& s : sockets) {  // the server closes each: reading ends (after any error message)
    std::vector<uint8_t> sink(1 << 16);
    boost::system::error_code ec;
    while (!ec) s.read_some(asio::buffer(sink), ec);
    EXPECT_TRUE(ec == asio::error::eof || ec == asio::error::connection_reset) << ec.message();
  }
  for (uint32_t seq = 1; seq <= 3; ++seq) EXPECT_EQ(good.fetch({seq, 0, {cell}, {}}).rows.rows.size(), 1u);
  const std::vector<std::string> lines = log();
  for (const auto& c : cases) {
    const std::string& reason = c.first;  // a named copy: clang 14 cannot capture a structured binding
    EXPECT_TRUE(std::any_of(lines.begin(), lines.end(), [&](const std::string& l) {
      return l.find("dropped") != std::string::npos && l.find(reason) != std::string::npos;
    })) << reason;
  }
  EXPECT_EQ(server_->stats().sessions_dropped, cases.size());
  // A client told the server's reason: a fetch of a cell that does not exist.
  EXPECT_THROW(good.fetch({9, 0, {999999}, {}}), Error);
}

// The command: serves for a while, says where, and stops by itself; a world without grid sets is
// refused with what to run.
TEST_F(PvsServerTest, ServeCommand) {
  const test::CommandResult r = test::run_cellwalk("serve " + inputs_->file("city.cww") + " --seconds 0.5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("on 127.0.0.1:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"sessions\": 0"), std::string::npos) << r.output;
  const test::CommandResult bare = test::run_cellwalk("serve " + inputs_->file("city.cwscene") + " --seconds 0.5");
  EXPECT_NE(bare.exit_code, 0);
  EXPECT_EQ(std::count(bare.output.begin(), bare.output.end(), '\n'), 1) << bare.output;
}

}  // namespace
}  // namespace cellwalk
