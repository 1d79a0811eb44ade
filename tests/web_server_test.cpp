// The browser side of `cellwalk serve --web` (issue 21; docs/protocol.md, "WebSocket"): the PVS
// streaming protocol over WebSockets on real loopback sockets, against the TCP server's answers
// and the world's bytes; the page's files served, and nothing outside their folder; hostile
// WebSocket peers dropped alone.
#include <gtest/gtest.h>

#include <utility>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <filesystem>
#include <fstream>
#include <thread>

#include "cellwalk/net/frame.hpp"
#include "cellwalk/net/web_listener.hpp"
#include "cellwalk/store/mesh_codec.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/pvs_stream/pvs_server.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using namespace pvs_stream;
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

// A blocking WebSocket peer: what a browser's page does, frame by frame.
class WsPeer {
 public:
  // `origin`: the page that opens it, as a browser names it ("": none, as a tool sends).
  explicit WsPeer(uint16_t port, const std::string& target = "/ws", const std::string& origin = "") : ws_(io_) {
    tcp::resolver resolver(io_);
    asio::connect(ws_.next_layer(), resolver.resolve("127.0.0.1", std::to_string(port)));
    ws_.binary(true);
    if (!origin.empty())
      ws_.set_option(websocket::stream_base::decorator([origin](websocket::request_type& r) { r.set(http::field::origin, origin); }));
    ws_.handshake("127.0.0.1", target);
  }
  void send(PvsMessage type, const std::vector<uint8_t>& payload) { ws_.write(asio::buffer(net::make_frame(uint8_t(type), payload))); }
  // The server may close before a hostile message is all sent: a failed write is no failure.
  void send_raw(const std::vector<uint8_t>& bytes, bool binary = true) {
    ws_.binary(binary);
    beast::error_code ec;
    ws_.write(asio::buffer(bytes), ec);
    ws_.binary(true);
  }
  // The next frame: its type and payload.
  std::pair<uint8_t, std::vector<uint8_t>> receive() {
    beast::flat_buffer buffer;
    ws_.read(buffer);
    const auto data = buffer.cdata();
    const std::span<const uint8_t> bytes(static_cast<const uint8_t*>(data.data()), data.size());
    const net::FrameHeader h = net::parse_frame_header(bytes.first(net::kFrameHeaderBytes), 1u << 30);
    EXPECT_EQ(h.length, bytes.size() - net::kFrameHeaderBytes);
    return {h.type, std::vector<uint8_t>(bytes.begin() + net::kFrameHeaderBytes, bytes.end())};
  }
  // Reads until the server closes; true when it did.
  bool closed_by_server() {
    beast::error_code ec;
    for (int i = 0; i < 100 && !ec; ++i) {
      beast::flat_buffer buffer;
      ws_.read(buffer, ec);
    }
    return bool(ec);
  }

 private:
  asio::io_context io_;
  websocket::stream<tcp::socket> ws_;
};

// One HTTP request; the status and body.
std::pair<int, std::string> http_request(uint16_t port, http::verb verb, const std::string& target) {
  asio::io_context io;
  tcp::socket socket(io);
  socket.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  http::request<http::empty_body> request(verb, target, 11);
  request.set(http::field::host, "127.0.0.1");
  http::write(socket, request);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.skip(verb == http::verb::head);
  http::read(socket, buffer, parser);
  return {int(parser.get().result_int()), parser.get().body()};
}

class WebServerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    inputs_ = new test::SharedInputs(
        "web-server-city", {"generate city --objects 40 --seed 3 -o {dir}/city.cwscene", "build {dir}/city.cwscene -o {dir}/city.cww --zstd",
                            "pvs {dir}/city.cww --engine conservative --cells grid:30"});
  }
  static void TearDownTestSuite() { delete inputs_; }

  void start(PvsServerOptions options = {}) {
    std::filesystem::create_directories(root_.path() / "src");
    std::ofstream(root_.file("index.html")) << "<!doctype html><title>cellwalk</title>";
    std::ofstream(root_.file("src/main.js")) << "export const x = 1;";
    std::ofstream(dir_.file("secret.txt")) << "outside the root";
    options.web = true;
    options.web_root = root_.path().string();
    options.log = [this](const std::string& line) {
      const std::lock_guard lock(log_mutex_);
      log_.push_back(line);
    };
    world_ = std::make_unique<World>(inputs_->file("city.cww"));
    server_ = std::make_unique<PvsServer>(*world_, options);
    thread_ = std::thread([this] { server_->run(); });
  }
  void TearDown() override {
    if (server_) server_->stop();
    if (thread_.joinable()) thread_.join();
  }
  bool logged(const std::string& a, const std::string& b) {
    const std::lock_guard lock(log_mutex_);
    return std::any_of(log_.begin(), log_.end(), [&](const std::string& l) { return l.find(a) != std::string::npos && l.find(b) != std::string::npos; });
  }

  static inline test::SharedInputs* inputs_ = nullptr;
  test::TempDir dir_, root_;
  std::unique_ptr<World> world_;
  std::unique_ptr<PvsServer> server_;
  std::thread thread_;
  std::mutex log_mutex_;
  std::vector<std::string> log_;
};

// The same welcome as over TCP, the catalog of every object, and a fetch answered with the rows
// and the objects, each the world's level with its zstd layer removed (the world is built with
// --zstd), decoding to the same mesh.
TEST_F(WebServerTest, WebSocketSessionsSpeakTheProtocolAndGetLevelsWithoutZstd) {
  start();
  const PvsClient tcp_client("127.0.0.1", server_->port());
  WsPeer peer(server_->web_port());
  peer.send(PvsMessage::hello, encode_hello());
  const auto [type, welcome] = peer.receive();
  ASSERT_EQ(type, uint8_t(PvsMessage::welcome));
  EXPECT_EQ(welcome, encode_welcome(tcp_client.welcome()));
  peer.send(PvsMessage::catalog_request, {});
  const auto [catalog_type, catalog_bytes] = peer.receive();
  ASSERT_EQ(catalog_type, uint8_t(PvsMessage::catalog));
  const Catalog catalog = parse_catalog(catalog_bytes);
  ASSERT_EQ(catalog.objects.size(), world_->object_count());
  for (uint32_t id = 0; id < world_->object_count(); ++id) {
    EXPECT_EQ(catalog.objects[id].color, world_->object(id).color);
    EXPECT_EQ(catalog.objects[id].box[0], world_->object(id).bounds.min.x);
    EXPECT_EQ(catalog.objects[id].box[5], world_->object(id).bounds.max.z);
  }
  uint32_t cell = kNoCell;
  for (uint32_t c : tcp_client.welcome().cells)
    if (c != kNoCell) cell = c;
  ASSERT_NE(cell, kNoCell);
  peer.send(PvsMessage::fetch, encode_fetch({7, 0, {cell}, {}}));
  const auto [rows_type, rows_bytes] = peer.receive();
  ASSERT_EQ(rows_type, uint8_t(PvsMessage::rows));
  const RowsReply rows = parse_rows(rows_bytes);
  ASSERT_EQ(rows.rows.size(), 1u);
  size_t objects = 0;
  for (;;) {
    const auto [t, payload] = peer.receive();
    if (t == uint8_t(PvsMessage::done)) {
      EXPECT_EQ(parse_done(payload).objects, objects);
      break;
    }
    ASSERT_EQ(t, uint8_t(PvsMessage::object));
    const ObjectReply o = parse_object(payload);
    const std::vector<uint8_t> stored = world_->read_level(o.id, o.level);
    EXPECT_NE(o.bytes, stored) << "object " << o.id << ": the world is built with --zstd, the browser gets it without";
    const Mesh sent = decode_mesh(o.bytes, "sent"), truth = decode_mesh(stored, "stored");
    EXPECT_EQ(sent.positions, truth.positions) << "object " << o.id;
    EXPECT_EQ(sent.indices, truth.indices) << "object " << o.id;
    EXPECT_EQ(o.bytes[5] & 4, 0) << "the zstd flag";
    ++objects;
  }
  EXPECT_EQ(objects, rows.rows[0].second.size());
  EXPECT_EQ(server_->stats().web_sessions, 1u);
}

// The page's files, and nothing else: paths out of the folder (plain, encoded, through a link),
// other methods and WebSockets elsewhere than /ws are refused with a status and a log line.
TEST_F(WebServerTest, ServesTheFolderAndNothingOutsideIt) {
  start();
  const uint16_t port = server_->web_port();
  EXPECT_EQ(http_request(port, http::verb::get, "/"), (std::pair<int, std::string>{200, "<!doctype html><title>cellwalk</title>"}));
  EXPECT_EQ(http_request(port, http::verb::get, "/src/main.js?v=2").second, "export const x = 1;");
  EXPECT_EQ(http_request(port, http::verb::head, "/src/main.js").first, 200);
  std::filesystem::create_symlink(dir_.file("secret.txt"), root_.file("link.txt"));
  for (const std::string target : {"/../secret.txt", "/%2e%2e/secret.txt", "/src/../../secret.txt", "/link.txt", "/missing.js", "/%zz", "/a\\b"})
    EXPECT_EQ(http_request(port, http::verb::get, target).first, 404) << target;
  EXPECT_EQ(http_request(port, http::verb::post, "/").first, 405);
  EXPECT_THROW(WsPeer(port, "/elsewhere"), beast::system_error);
  EXPECT_TRUE(logged("web:", "not /ws"));
  // Only this server's own page may open a WebSocket (beast's client sends Host "127.0.0.1").
  EXPECT_THROW(WsPeer(port, "/ws", "http://another.example"), beast::system_error);
  EXPECT_TRUE(logged("web:", "another site"));
  EXPECT_NO_THROW(WsPeer(port, "/ws", "http://127.0.0.1"));
  EXPECT_EQ(net::web_file_for(root_.path().string(), "/"), (std::filesystem::canonical(root_.path()) / "index.html").string());
  EXPECT_EQ(net::web_file_for(root_.path().string(), "/link.txt"), "");
}

// Hostile WebSocket peers: another magic, a text message, a frame whose length is not its
// message's, a message over the limit, a fetch before the hello, the catalog asked for again (a
// peer could make the server queue it without end): each session is dropped with
// its reason logged, and a page beside them goes on being served.
TEST_F(WebServerTest, HostileWebSocketSessionsAreDroppedAlone) {
  start();
  const uint16_t port = server_->web_port();
  WsPeer good(port);
  good.send(PvsMessage::hello, encode_hello());
  EXPECT_EQ(good.receive().first, uint8_t(PvsMessage::welcome));
  std::vector<uint8_t> short_frame = net::make_frame(uint8_t(PvsMessage::hello), encode_hello());
  short_frame.pop_back();
  const std::vector<std::pair<std::string, std::function<void(WsPeer&)>>> cases = {
      {"bad magic", [](WsPeer& p) { p.send_raw(std::vector<uint8_t>(32, 'x')); }},
      {"a text message", [](WsPeer& p) { p.send_raw(net::make_frame(uint8_t(PvsMessage::hello), encode_hello()), false); }},
      {"whose frame says", [&](WsPeer& p) { p.send_raw(short_frame); }},
      {"more than the", [](WsPeer& p) { p.send_raw(std::vector<uint8_t>(3u << 20, 0)); }},
      {"first message must be hello", [](WsPeer& p) { p.send(PvsMessage::fetch, encode_fetch({1, 0, {0}, {}})); }},
      {"a second catalog request", [](WsPeer& p) {
         p.send(PvsMessage::hello, encode_hello());
         p.send(PvsMessage::catalog_request, {});
         p.send(PvsMessage::catalog_request, {});
       }}};
  for (const auto& [reason, act] : cases) {
    WsPeer bad(port);
    act(bad);
    EXPECT_TRUE(bad.closed_by_server()) << reason;
  }
  good.send(PvsMessage::catalog_request, {});
  EXPECT_EQ(good.receive().first, uint8_t(PvsMessage::catalog));
  for (const auto& c : cases) EXPECT_TRUE(logged("dropped", c.first)) << c.first;
}

// The command: --web prints where the page is, and refuses a folder that is not the client's.
TEST_F(WebServerTest, ServeCommandWithWeb) {
  if (!std::filesystem::is_directory(test::source_path("web/node_modules/three")))
    GTEST_SKIP() << "web/node_modules is not installed (scripts/setup runs npm ci)";
  const test::CommandResult r =
      test::run_cellwalk("serve " + inputs_->file("city.cww") + " --web --seconds 0.5 --json --web-root " + test::source_path("web"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("browser client at http://127.0.0.1:"), std::string::npos) << r.output;
  const test::CommandResult empty = test::run_cellwalk("serve " + inputs_->file("city.cww") + " --web --seconds 0.5 --web-root " + dir_.path().string());
  EXPECT_NE(empty.exit_code, 0);
  EXPECT_NE(empty.output.find("no browser client here"), std::string::npos) << empty.output;
  EXPECT_EQ(std::count(empty.output.begin(), empty.output.end(), '\n'), 1) << empty.output;
}

}  // namespace
}  // namespace cellwalk
