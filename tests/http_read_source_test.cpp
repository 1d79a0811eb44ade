// A world behind a plain web server (issue 20): HttpReadSource against Debian's nginx with the
// file's own bytes as the oracle, a world opened by URL against the same world opened from its
// file, the PVS streaming walkthrough served by nginx against the dedicated server, and servers
// that lie, refuse or say nothing, each refused in one line that names the URL.
#include <gtest/gtest.h>

// Boost 1.74's Asio uses std::exchange without including <utility>.
#include <utility>
#include <boost/asio.hpp>
#include <filesystem>
#include <set>
#include <thread>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/store/http_read_source.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/pvs_stream/pvs_server.hpp"
#include "experiments/common/web_server.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;

std::string http_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// Every range, from any thread, is the file's bytes there; the counters count the requests.
TEST(HttpReadSource, EveryRangeIsTheFilesBytes) {
  const test::TempDir dir;
  std::filesystem::create_directories(dir.file("www"));
  std::vector<uint8_t> bytes(300000);
  Random rng(7);
  for (uint8_t& b : bytes) b = uint8_t(rng.integer(0, 255));
  test::spit(dir.file("www/blob.bin"), bytes);
  const bench::WebServer web(dir.file("www"), dir.file("nginx"));
  HttpReadSource source(web.url("blob.bin"));
  EXPECT_EQ(source.size(), bytes.size());
  const auto check = [&](uint64_t seed, int reads) {
    Random r(seed);
    for (int i = 0; i < reads; ++i) {
      const uint64_t offset = uint64_t(r.integer(0, int64_t(bytes.size()) - 1));
      const size_t length = size_t(r.integer(1, 70000));
      std::vector<uint8_t> got(length, 0xAB);
      const long n = source.read_at(got.data(), length, offset);
      const size_t expected = std::min<size_t>(length, bytes.size() - offset);
      ASSERT_EQ(n, long(expected)) << "offset " << offset;
      EXPECT_TRUE(std::equal(got.begin(), got.begin() + long(expected), bytes.begin() + long(offset))) << "offset " << offset;
    }
  };
  check(1, 50);
  std::vector<std::thread> threads;
  for (uint64_t t = 0; t < 4; ++t) threads.emplace_back([&, t] { check(10 + t, 25); });
  for (std::thread& t : threads) t.join();
  uint8_t none = 0;
  EXPECT_EQ(source.read_at(&none, 1, bytes.size()), 0);
  const HttpCounters c = source.counters();
  EXPECT_EQ(c.requests, 1u + 50 + 4 * 25);  // the size probe, then one request a read
  EXPECT_LE(c.connections, 5u);             // kept alive: one a thread at most
}

// A world opened by URL is the world: the same objects, the same bytes of every level, and the
// commands take the URL where they take a file.
TEST(HttpReadSource, AWorldByUrlIsTheWorldFromItsFile) {
  const test::TempDir dir;
  std::filesystem::create_directories(dir.file("www"));
  const std::string file = test::write_street_world(dir, 12);
  std::filesystem::copy_file(file, dir.file("www/city.cww"));
  const bench::WebServer web(dir.file("www"), dir.file("nginx"));
  const World local(file), remote(web.url("city.cww"));
  ASSERT_EQ(remote.object_count(), local.object_count());
  EXPECT_EQ(remote.triangle_count(), local.triangle_count());
  for (ObjectId id = 0; id < local.object_count(); ++id)
    for (uint32_t level = 0; level < local.object(id).lod_count; ++level)
      EXPECT_EQ(remote.read_level(id, level), local.read_level(id, level)) << id << "/" << level;
  EXPECT_TRUE(is_world_file(web.url("city.cww")));
  const test::CommandResult info = test::run_cellwalk("info " + web.url("city.cww") + " --json");
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("\"objects\": " + std::to_string(local.object_count())), std::string::npos) << info.output;
  const test::CommandResult verify = test::run_cellwalk("verify " + web.url("city.cww"));
  EXPECT_EQ(verify.exit_code, 0) << verify.output;
  // Any strategy walks it: brute draws the same triangles from the URL as from the file.
  const test::CommandResult path = test::run_cellwalk("path " + web.url("city.cww") + " --frames 20 -o " + dir.file("p.path"));
  ASSERT_EQ(path.exit_code, 0) << path.output;
  const auto triangles = [&](const std::string& world, const std::string& out) {
    const test::CommandResult r = test::run_cellwalk("walk " + world + " --path " + dir.file("p.path") + " --strategy brute -o " +
                                                     dir.file(out) + " --json");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json run = test::only_run(r);
    return run["total_triangles"].get<uint64_t>();
  };
  const uint64_t from_url = triangles(web.url("city.cww"), "url"), from_file = triangles(file, "file");
  EXPECT_GT(from_url, 0u);
  EXPECT_EQ(from_url, from_file);
}

// A file damaged on the server fails its page checksum; one replaced while open is refused as
// changed; a missing file, a closed port and https say so, each in one line naming the URL.
TEST(HttpReadSource, DamageAndAbsenceAreOneLineNamingTheUrl) {
  const test::TempDir dir;
  std::filesystem::create_directories(dir.file("www"));
  const std::string file = test::write_street_world(dir, 12);
  std::filesystem::copy_file(file, dir.file("www/city.cww"));
  const bench::WebServer web(dir.file("www"), dir.file("nginx"));
  const std::string url = web.url("city.cww");

  const World open(url);
  std::vector<uint8_t> bytes = test::slurp(file);
  bytes[bytes.size() / 2] ^= 0x5A;
  test::spit(dir.file("www/city.cww.new"), bytes);
  // The same size; a later time, so nginx's validator changes even within one second.
  std::filesystem::last_write_time(dir.file("www/city.cww.new"),
                                   std::filesystem::last_write_time(dir.file("www/city.cww")) + std::chrono::seconds(10));
  std::filesystem::rename(dir.file("www/city.cww.new"), dir.file("www/city.cww"));
  std::string e = http_error([&] {
    for (ObjectId id = 0; id < open.object_count(); ++id) open.read_level(id, 0);
  });
  EXPECT_NE(e.find(url), std::string::npos) << e;
  EXPECT_NE(e.find("changed"), std::string::npos) << e;

  e = http_error([&] { World(url).file().verify(); });
  EXPECT_NE(e.find(url), std::string::npos) << e;
  EXPECT_TRUE(e.find("checksum") != std::string::npos || e.find("damaged") != std::string::npos) << e;

  e = http_error([&] { const World w(web.url("nothing.cww")); });
  EXPECT_NE(e.find("404"), std::string::npos) << e;
  EXPECT_NE(e.find("check the URL"), std::string::npos) << e;
  EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 0) << e;

  asio::io_context io;
  tcp::acceptor closed(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  const uint16_t port = closed.local_endpoint().port();
  closed.close();
  e = http_error([&] { HttpReadSource s("http://127.0.0.1:" + std::to_string(port) + "/w.cww"); });
  EXPECT_NE(e.find("is the web server running"), std::string::npos) << e;
  EXPECT_NE(http_error([&] { HttpReadSource s("https://127.0.0.1/w.cww"); }).find("https is not supported"), std::string::npos);
  for (const char* bad : {"http://", "http://:80/w", "http://h:0/w", "http://h:99999/w", "http://h:x/w", "http://[::1]/w"})
    EXPECT_NE(http_error([&] { parse_http_url(bad); }).find(bad), std::string::npos) << bad;
  EXPECT_EQ(parse_http_url("http://host:81/a/b.cww?x=1").target, "/a/b.cww?x=1");
  EXPECT_EQ(parse_http_url("http://host").port, 80);

  const test::CommandResult walk = test::run_cellwalk("info " + web.url("nothing.cww"));
  EXPECT_NE(walk.exit_code, 0);
  EXPECT_EQ(std::count(walk.output.begin(), walk.output.end(), '\n'), 1) << walk.output;
}

// A peer that is not a range server: it answers each request with `answer` (after reading the
// request's head), or never, on one connection at a time, until stopped.
class FakeHttpServer {
 public:
  explicit FakeHttpServer(std::string answer) : answer_(std::move(answer)) {
    thread_ = std::thread([this] {
      for (;;) {
        tcp::socket s(io_);
        boost::system::error_code ec;
        acceptor_.accept(s, ec);
        if (ec || stopping_) return;
        asio::streambuf head;
        asio::read_until(s, head, "\r\n\r\n", ec);
        if (!answer_.empty()) asio::write(s, asio::buffer(answer_), ec);
        else held_.push_back(std::move(s));  // silence: keep it open
      }
    });
  }
  ~FakeHttpServer() {
    stopping_ = true;
    tcp::socket poke(io_);
    boost::system::error_code ec;
    poke.connect(acceptor_.local_endpoint(), ec);
    thread_.join();
  }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(acceptor_.local_endpoint().port()) + "/w.cww"; }

 private:
  asio::io_context io_;
  tcp::acceptor acceptor_{io_, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)};
  std::string answer_;
  std::atomic<bool> stopping_{false};
  std::vector<tcp::socket> held_;
  std::thread thread_;
};

TEST(HttpReadSource, ServersThatLieOrSayNothingAreRefused) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"HTTP/1.1 200 OK\r\nContent-Length: 5\r\n\r\nhello", "whole file (200)"},
      {"HTTP/1.1 206 Partial Content\r\nContent-Range: bytes 5-5/100\r\nContent-Length: 1\r\n\r\nx", "the server sent"},
      {"HTTP/1.1 206 Partial Content\r\nContent-Range: bytes 0-0/100\r\nContent-Length: 3\r\n\r\nxyz", "with 3 bytes"},
      {"HTTP/1.1 206 Partial Content\r\nContent-Length: 1\r\n\r\nx", "the server sent \"\""},
      {"HTTP/1.1 500 Internal Server Error\r\nContent-Length: 0\r\n\r\n", "answered 500"},
      {"SMTP ready\r\n\r\n", "bad"},
      {"", "no answer within 300 ms"}};
  for (const auto& c : cases) {
    const std::string& expected = c.second;
    SCOPED_TRACE(expected);
    const FakeHttpServer server(c.first);
    const std::string e = http_error([&] { HttpReadSource s(server.url(), 300); });
    EXPECT_NE(e.find(server.url()), std::string::npos) << e;
    EXPECT_NE(e.find(expected), std::string::npos) << e;
  }
}

TEST(HttpReadSource, ContentRangeIsParsedExactly) {
  const auto cr = parse_content_range("bytes 10-19/100");
  ASSERT_TRUE(cr);
  EXPECT_EQ(cr->first, 10u);
  EXPECT_EQ(cr->last, 19u);
  EXPECT_EQ(cr->total, 100u);
  for (const char* bad : {"", "bytes", "bytes 10-19", "bytes 19-10/100", "bytes 10-100/100", "bytes */100", "bytes 1-2/x",
                          "items 1-2/3", "bytes  1-2/3", "bytes 1-2/3 ", "bytes -1-2/3", "bytes 99999999999999999999-1/2"})
    EXPECT_FALSE(parse_content_range(bad)) << bad;
}

// The world file on a web server is the PVS server's equal: fetch for fetch, PvsFileSource over
// nginx returns the server's rows and objects (the oracle: the dedicated server over a socket).
TEST(HttpReadSource, TheFileSourceAnswersAsTheServerDoes) {
  const test::TempDir dir;
  std::filesystem::create_directories(dir.file("www"));
  const std::string file = test::write_street_world(dir, 16);
  const test::CommandResult pvs = test::run_cellwalk("pvs " + file + " --engine conservative --cells grid:30");
  ASSERT_EQ(pvs.exit_code, 0) << pvs.output;
  std::filesystem::copy_file(file, dir.file("www/city.cww"));
  const bench::WebServer web(dir.file("www"), dir.file("nginx"));
  const World local(file), remote(web.url("city.cww"));
  pvs_stream::PvsServer server(local, {});
  std::thread thread([&] { server.run(); });
  pvs_stream::PvsClient client("127.0.0.1", server.port());
  pvs_stream::PvsFileSource source(remote);
  EXPECT_EQ(source.welcome().cells, client.welcome().cells);
  std::vector<uint32_t> cells;
  for (uint32_t c : client.welcome().cells)
    if (c != pvs_stream::kNoCell) cells.push_back(c);
  ASSERT_GE(cells.size(), 2u);
  Random rng(3);
  std::set<uint32_t> held;
  for (uint32_t seq = 1; seq <= 5; ++seq) {
    pvs_stream::FetchRequest f{seq, seq % 2, {}, {}};
    for (int k = 0; k < 2; ++k) f.cells.push_back(cells[rng.integer(0, int64_t(cells.size()) - 1)]);
    for (uint32_t id : held)
      if (rng.chance(0.4)) f.dropped.push_back(id);
    for (uint32_t id : f.dropped) held.erase(id);
    const pvs_stream::PvsReply a = client.fetch(f), b = source.fetch(f);
    EXPECT_EQ(a.rows.rows, b.rows.rows);
    ASSERT_EQ(a.objects.size(), b.objects.size());
    for (size_t i = 0; i < a.objects.size(); ++i) {
      EXPECT_EQ(a.objects[i].id, b.objects[i].id);
      EXPECT_EQ(a.objects[i].level, b.objects[i].level);
      EXPECT_EQ(a.objects[i].bytes, b.objects[i].bytes);
      held.insert(a.objects[i].id);
    }
    EXPECT_GT(b.bytes, 0u);
  }
  server.stop();
  thread.join();
}

}  // namespace
}  // namespace cellwalk
