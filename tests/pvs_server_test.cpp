// The PVS streaming server and client over real loopback sockets (seed 004, §7.3–7.4 over TCP):
// fetches against the stored sets and the world's bytes, the server's mirror of what a client
// holds, delays that are real, and hostile sessions dropped alone.
#include <gtest/gtest.h>

// Boost 1.74's Asio uses std::exchange without including <utility>.
#include <utility>
#include <boost/asio.hpp>
#include <chrono>
#include <filesystem>
#include <set>
#include <thread>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/net/frame.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/pvs_stream/pvs_server.hpp"
#include "cellwalk/systems/pvs_stream_client/pvs_stream_strategy.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "experiments/common/web_server.hpp"
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
                            "pvs {dir}/city.cww --engine conservative --cells grid:30",
                            "path {dir}/city.cww --kind fast --frames 600 -o {dir}/fast.path"});
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

// ---- The client as a strategy ------------------------------------------------------------

// One frame the streaming client chose.
struct StreamedFrame {
  Camera camera;
  std::optional<uint32_t> cell;
  std::set<uint32_t> drawn;
};

class PvsStreamClientTest : public PvsServerTest {
 protected:
  void SetUp() override { world_ = std::make_unique<World>(inputs_->file("city.cww")); }

  std::unique_ptr<PvsStreamStrategy> client(const std::string& name, uint64_t budget = 0) {
    StrategyOptions options;
    options.memory_budget_bytes = budget;
    return std::make_unique<PvsStreamStrategy>(*world_, parse_pvs_stream_strategy_name(name), options);
  }

  // Every frame of the fast path (or its first `frames`): selects, then fetches every item's
  // mesh as the renderer would, checking it is the level the item names.
  std::vector<StreamedFrame> stream(PvsStreamStrategy& s, size_t frames = SIZE_MAX) {
    const CameraPath path = read_path(inputs_->file("fast.path"));
    std::vector<StreamedFrame> out;
    Camera camera;
    for (size_t i = 0; i < std::min(frames, path.frames.size()); ++i) {
      apply(path.frames[i], camera);
      std::vector<DrawItem> items;
      FrameStats stats;
      stats.time = path.frames[i].time;
      s.select(camera, items, stats);
      StreamedFrame f{camera, s.cell_id(camera), {}};
      for (const DrawItem& item : items) {
        const Mesh* mesh = s.mesh(item, stats);
        EXPECT_NE(mesh, nullptr) << "object " << item.id;
        if (mesh) {
          EXPECT_EQ(mesh->triangle_count(), world_->lod(item.id, item.lod).triangles) << "object " << item.id;
        }
        f.drawn.insert(item.id);
      }
      out.push_back(std::move(f));
    }
    return out;
  }

  // The oracle: the stored set of the frame's cell, culled to its frustum.
  std::set<uint32_t> expected(const StreamedFrame& f) const {
    const visibility::StoredPvs pvs(*world_);
    std::set<uint32_t> out;
    const auto set = pvs.set(*f.cell);
    if (!set) return out;
    const Frustum frustum(f.camera);
    for (uint32_t id : set->objects)
      if (frustum.intersects(world_->object(id).bounds)) out.insert(id);
    return out;
  }

  // Frames that stand in a view cell and drew exactly its culled stored set.
  size_t exact_frames(const std::vector<StreamedFrame>& frames) const {
    size_t n = 0;
    for (const StreamedFrame& f : frames) {
      if (!f.cell) continue;
      const std::set<uint32_t> e = expected(f);
      EXPECT_EQ(f.drawn, e) << "cell " << *f.cell;
      n += f.drawn == e;
    }
    return n;
  }
};

// With every reply in time, each frame draws its cell's stored set, culled, from geometry that
// came over the socket; every prefetcher, the strategy's own server and a running one.
TEST_F(PvsStreamClientTest, EachFrameDrawsItsCellsStoredSet) {
  start();
  for (const std::string& name : std::vector<std::string>{"pvs-stream:prefetch=snp,pace=0", "pvs-stream:prefetch=pbnp,pace=0",
                                 "pvs-stream:prefetch=speed,pace=0",
                                 "pvs-stream:pace=0,server=127.0.0.1:" + std::to_string(server_->port())}) {
    SCOPED_TRACE(name);
    auto s = client(name);
    const std::vector<StreamedFrame> frames = stream(*s);
    EXPECT_GT(exact_frames(frames), frames.size() / 2);
    const PvsStreamCounters c = s->counters();
    EXPECT_EQ(c.late_frames, 0u);
    EXPECT_GE(c.cell_crossings, 3u);
    EXPECT_GE(c.transactions, 2u);
    EXPECT_GT(c.objects_received, 0u);
    EXPECT_GT(c.bytes_received, c.objects_received * 12);
    EXPECT_LE(s->resident_bytes(), s->peak_resident_bytes());
  }
  // The running server sent what that client received, and saw it close.
  EXPECT_GE(server_->stats().fetches, 2u);
}

// Over a slow link a frame that crosses into a cell whose row has not come waits for it (a
// stall) and still draws exactly that cell's set; told not to wait, it draws the last row it had
// and counts the frame late.
TEST_F(PvsStreamClientTest, ALateRowStallsTheFrameOrIsCountedLate) {
  auto waits = client("pvs-stream:prefetch=snp,pace=0,latency_ms=120,wait_ms=20000");
  const std::vector<StreamedFrame> frames = stream(*waits);
  EXPECT_GT(exact_frames(frames), frames.size() / 2);
  EXPECT_GT(waits->counters().stall_frames, 0u);
  EXPECT_EQ(waits->counters().late_frames, 0u);
  EXPECT_GE(waits->counters().startup_ms, 240.0);  // a round trip at least

  auto hurries = client("pvs-stream:prefetch=snp,pace=0,latency_ms=120,wait_ms=0");
  stream(*hurries);
  EXPECT_GT(hurries->counters().late_frames, 0u);
  EXPECT_EQ(hurries->counters().late_frames, hurries->counters().stall_frames);
}

// A memory budget bounds the client's store: rows other than the current cell's go first, the
// frames still draw their cells' sets; a budget below one cell's objects stops with what to do.
TEST_F(PvsStreamClientTest, TheBudgetBoundsTheStore) {
  auto unbounded = client("pvs-stream:pace=0");
  stream(*unbounded);
  const uint64_t peak = unbounded->peak_resident_bytes();
  // Between the largest cell's own objects (decoded, with its row) and the unbounded peak.
  const visibility::StoredPvs pvs(*world_);
  uint64_t largest = 0;
  for (CellId c = 0; c < pvs.partition().cell_count(); ++c) {
    const auto set = pvs.partition().cell(c).computed() ? pvs.set(c) : std::nullopt;
    if (!set) continue;
    uint64_t bytes = set->objects.size() * sizeof(uint32_t);
    for (uint32_t id : set->objects) bytes += world_->decode_level(id, 0, world_->read_level(id, 0)).byte_size();
    largest = std::max(largest, bytes);
  }
  ASSERT_LT(largest, peak) << "one cell sees the whole store: no budget between them to test";
  const uint64_t budget = (largest + peak) / 2;
  auto bounded = client("pvs-stream:pace=0", budget);
  const std::vector<StreamedFrame> frames = stream(*bounded);
  EXPECT_GT(exact_frames(frames), frames.size() / 2);
  EXPECT_LE(bounded->peak_resident_bytes(), budget);
  EXPECT_GE(bounded->counters().cache_swaps, unbounded->counters().cache_swaps);

  auto starved = client("pvs-stream:pace=0", 1024);
  try {
    stream(*starved);
    FAIL() << "a 1 KiB budget held a cell's objects";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("raise --budget"), std::string::npos) << e.what();
  }
}

// Names the strategy refuses, each with what to write instead.
// The same walkthrough with no PVS server: the world file behind Debian's nginx, its rows and
// objects read by HTTP range requests; every frame again draws its cell's stored set.
TEST_F(PvsStreamClientTest, AWebServerServesTheSameWalk) {
  const test::TempDir work;
  const std::string file = inputs_->file("city.cww");
  const bench::WebServer web(std::filesystem::path(file).parent_path().string(), work.file("nginx"));
  auto s = client("pvs-stream:pace=0,server=" + web.url("city.cww"));
  const std::vector<StreamedFrame> frames = stream(*s);
  EXPECT_GT(exact_frames(frames), frames.size() / 2);
  const PvsStreamCounters c = s->counters();
  EXPECT_EQ(c.late_frames, 0u);
  EXPECT_GE(c.transactions, 2u);
  EXPECT_GT(c.objects_received, 0u);
  EXPECT_GE(c.bytes_received, c.objects_received * 12);  // whole pages: at least the objects' bytes
  const std::string wrong = web.url("elsewhere.cww");
  try {
    client("pvs-stream:server=" + wrong);
    ADD_FAILURE() << "a missing file was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("404"), std::string::npos) << e.what();
  }
}

TEST(PvsStreamStrategyName, BadSettingsAreRefused) {
  EXPECT_EQ(parse_pvs_stream_strategy_name("pvs-stream").prefetch, PvsStreamConfig::Prefetch::kPbnp);
  EXPECT_EQ(parse_pvs_stream_strategy_name("pvs-stream:prefetch=speed").band, 0.05);
  const PvsStreamConfig c = parse_pvs_stream_strategy_name("pvs-stream:server=localhost:7000,entries=12");
  EXPECT_EQ(c.host, "localhost");
  EXPECT_EQ(c.port, 7000);
  EXPECT_EQ(c.entries, 12);
  EXPECT_EQ(parse_pvs_stream_strategy_name("pvs-stream:server=http://127.0.0.1:8080/w.cww,latency_ms=40").url,
            "http://127.0.0.1:8080/w.cww");
  for (const std::string bad : {"pvs-stream:prefetch=psychic", "pvs-stream:prefetch=snp,entries=8", "pvs-stream:entries=3",
                                "pvs-stream:prefetch=snp,band=0.2", "pvs-stream:band=0.5", "pvs-stream:server=7000",
                                "pvs-stream:server=host:70000", "pvs-stream:server=h:1,latency_ms=5", "pvs-stream:pace=2",
                                "pvs-stream:colour=red", "pvs-stream:server=http://h:0/w.cww", "pvs-stream:server=https://h/w"}) {
    try {
      parse_pvs_stream_strategy_name(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

// The command line: walk streams the world from the strategy's own server.
TEST_F(PvsStreamClientTest, WalkStreamsTheWorld) {
  const test::TempDir out;
  const test::CommandResult r = test::run_cellwalk("walk " + inputs_->file("city.cww") + " --path " + inputs_->file("fast.path") +
                                                   " --strategy pvs-stream:latency_ms=5,pace=0 -o " + out.file("walk") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pvs-stream"), std::string::npos) << r.output;
  const nlohmann::json run = test::only_run(r);
  ASSERT_TRUE(run.contains("strategy_counters")) << r.output;
  EXPECT_GE(run["strategy_counters"]["transactions"].get<double>(), 1.0) << r.output;
  EXPECT_GT(run["strategy_counters"]["bytes_received"].get<double>(), 0.0) << r.output;
  EXPECT_EQ(run["strategy_counters"]["stall_frames"].get<double>(), double(run["stalls"].get<uint64_t>())) << r.output;
}

}  // namespace
}  // namespace cellwalk
