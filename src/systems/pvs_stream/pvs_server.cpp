// Seed 004 (Zheng), §7.3–7.4 over TCP: the PVS streaming server and a blocking client.
#include "cellwalk/systems/pvs_stream/pvs_server.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "cellwalk/core/error.hpp"
#include "cellwalk/net/web_listener.hpp"
#include "cellwalk/store/mesh_codec.hpp"
#include "cellwalk/store/page_file.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"

namespace cellwalk::pvs_stream {

namespace asio = boost::asio;
using asio::ip::tcp;

Welcome grid_of(const World& world) {
  const visibility::StoredPvs pvs(world);
  const ViewCellPartition& p = pvs.partition();
  const std::string where = world.file().path();
  if (p.kind() != "grid" || p.cell_count() == 0)
    fail(where, "its visible sets are over " + p.kind() + " cells; PVS streaming steps over a grid: rerun `cellwalk pvs " +
                    where + " --cells grid:SIZE`");
  Welcome w;
  w.objects = uint32_t(world.object_count());
  w.cell_count = uint32_t(p.cell_count());
  w.origin_x = w.origin_z = INFINITY;
  for (size_t c = 0; c < p.cell_count(); ++c) {
    const Aabb& b = p.cell(CellId(c)).box;
    w.origin_x = std::min(w.origin_x, double(b.min.x));
    w.origin_z = std::min(w.origin_z, double(b.min.z));
    w.cell_size = std::max({w.cell_size, double(b.size().x), double(b.size().z)});
  }
  std::vector<std::pair<uint32_t, uint32_t>> at(p.cell_count());
  for (size_t c = 0; c < p.cell_count(); ++c) {
    const Aabb& b = p.cell(CellId(c)).box;
    at[c] = {uint32_t(std::lround((b.min.z - w.origin_z) / w.cell_size)), uint32_t(std::lround((b.min.x - w.origin_x) / w.cell_size))};
    w.rows = std::max(w.rows, at[c].first + 1);
    w.cols = std::max(w.cols, at[c].second + 1);
  }
  w.cells.assign(size_t(w.rows) * w.cols, kNoCell);
  for (size_t c = 0; c < p.cell_count(); ++c) {
    uint32_t& slot = w.cells[size_t(at[c].first) * w.cols + at[c].second];
    if (slot != kNoCell)
      fail(where, "its grid of view cells has layers in height; PVS streaming needs a 2D grid (`cellwalk pvs --cells grid:SIZE` on a city)");
    if (p.cell(CellId(c)).computed()) slot = uint32_t(c);
  }
  return w;
}

Catalog catalog_of(const World& world) {
  Catalog c;
  c.objects.resize(world.object_count());
  for (size_t id = 0; id < c.objects.size(); ++id) {
    const auto& o = world.object(uint32_t(id));
    c.objects[id].color = o.color;
    std::copy_n(&o.bounds.min.x, 3, c.objects[id].box);
    std::copy_n(&o.bounds.max.x, 3, c.objects[id].box + 3);
  }
  return c;
}

PlannedReply plan_reply(const visibility::StoredPvs& pvs, std::vector<uint8_t>& held, const FetchRequest& f) {
  for (uint32_t id : f.dropped) held[id] = 0;
  PlannedReply out{{f.sequence, {}}, {}};
  std::vector<uint32_t> wanted;
  for (uint32_t cell : f.cells) {
    if (!pvs.partition().cell(cell).computed())
      throw net::ProtocolError("cell " + std::to_string(cell) + " has no visible set (solid or skipped)");
    std::vector<uint32_t> ids;
    if (const auto set = pvs.set(cell)) ids.assign(set->objects.begin(), set->objects.end());
    wanted.insert(wanted.end(), ids.begin(), ids.end());
    out.rows.rows.emplace_back(cell, std::move(ids));
  }
  std::sort(wanted.begin(), wanted.end());
  wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
  for (uint32_t id : wanted)
    if (!held[id]) {
      held[id] = 1;
      out.send.push_back(id);
    }
  return out;
}

// ---- The server --------------------------------------------------------------------------

struct PvsServer::Impl {
  struct Session {
    uint64_t id = 0;
    std::shared_ptr<net::Connection> connection;
    std::vector<uint8_t> held;  // the server's mirror of the client's objects
    bool greeted = false;
    bool web = false;  // a browser: levels go without zstd
    bool catalogued = false;
  };

  const World& world;
  visibility::StoredPvs pvs;
  Welcome welcome;
  std::vector<uint8_t> catalog;  // encoded once, sent to whoever asks
  PvsServerOptions options;
  asio::io_context io;
  net::Listener listener;
  std::optional<net::WebListener> web;
  std::map<uint64_t, std::shared_ptr<Session>> sessions;
  uint64_t next_id = 1;
  mutable std::mutex stats_mutex;
  PvsServerStats stats;

  Impl(const World& w, PvsServerOptions o)
      : world(w), pvs(w), welcome(grid_of(w)), catalog(encode_catalog(catalog_of(w))), options(std::move(o)),
        listener(io, options.port) {
    std::error_code ec;
    welcome.world_bytes = std::filesystem::file_size(world.file().path(), ec);
    if (options.web)
      web.emplace(io, net::WebListenerOptions{options.web_port, "127.0.0.1", options.web_root, options.link,
                                              options.limits, size_t(64) << 20, options.log});
  }

  void log(const std::string& line) const {
    if (options.log) options.log(line);
  }

  void open(std::shared_ptr<net::Connection> connection, bool from_web) {
    auto s = std::make_shared<Session>();
    s->id = next_id++;
    s->connection = std::move(connection);
    s->web = from_web;
    s->held.assign(world.object_count(), 0);
    sessions[s->id] = s;
    {
      const std::lock_guard lock(stats_mutex);
      ++stats.sessions_opened;
      if (from_web) ++stats.web_sessions;
    }
    log("session " + std::to_string(s->id) + (from_web ? " opened (WebSocket)" : " opened"));
    std::weak_ptr<Session> weak = s;
    s->connection->start(
        [this, weak](uint8_t type, std::vector<uint8_t> payload) {
          if (auto session = weak.lock()) handle(*session, type, payload);
        },
        [this, id = s->id](const std::string& reason) { closed(id, reason); });
  }

  void closed(uint64_t id, const std::string& reason) {
    const auto it = sessions.find(id);
    if (it == sessions.end()) return;
    const bool orderly = reason == "the peer closed the connection";
    {
      const std::lock_guard lock(stats_mutex);
      stats.bytes_sent += it->second->connection->bytes_sent();
      if (!orderly) ++stats.sessions_dropped;
    }
    log("session " + std::to_string(id) + (orderly ? " closed" : " dropped: " + reason));
    // The connection calls this from inside itself: release the session after it returns.
    asio::post(io, [keep = it->second] {});
    sessions.erase(it);
  }

  void handle(Session& s, uint8_t type, const std::vector<uint8_t>& payload) {
    try {
      if (!s.greeted) {
        if (type != uint8_t(PvsMessage::hello)) throw net::ProtocolError("the first message must be hello");
        parse_hello(payload);
        s.greeted = true;
        s.connection->send(uint8_t(PvsMessage::welcome), encode_welcome(welcome));
        return;
      }
      if (type == uint8_t(PvsMessage::catalog_request)) {
        parse_catalog_request(payload);
        if (s.catalogued) throw net::ProtocolError("a second catalog request: the catalog is sent once a session");
        s.catalogued = true;
        s.connection->send(uint8_t(PvsMessage::catalog), catalog);
        return;
      }
      if (type != uint8_t(PvsMessage::fetch)) throw net::ProtocolError("unexpected message type " + std::to_string(type));
      fetch(s, parse_fetch(payload, welcome.cell_count, welcome.objects));
    } catch (const std::exception& e) {
      s.connection->send(uint8_t(PvsMessage::error), encode_error(e.what()));
      s.connection->close_after_sending(e.what());
    }
  }

  // §7.3: the rows asked for, then the geometry of their union less what the client holds.
  void fetch(Session& s, const FetchRequest& f) {
    PlannedReply plan = plan_reply(pvs, s.held, f);
    s.connection->send(uint8_t(PvsMessage::rows), encode_rows(plan.rows));
    for (uint32_t id : plan.send) {
      const uint32_t level = std::min(f.level, world.object(id).lod_count - 1);
      std::vector<uint8_t> bytes = world.read_level(id, level);
      if (s.web) bytes = without_zstd(bytes, world.file().path() + ": object " + std::to_string(id));
      s.connection->send(uint8_t(PvsMessage::object), encode_object({f.sequence, id, level, std::move(bytes)}));
    }
    const uint32_t sent = uint32_t(plan.send.size());
    s.connection->send(uint8_t(PvsMessage::done), encode_done({f.sequence, sent}));
    uint64_t session_bytes = 0;
    for (const auto& [id, other] : sessions) session_bytes += other->held.capacity() + other->connection->queued_bytes();
    const std::lock_guard lock(stats_mutex);
    ++stats.fetches;
    stats.objects_sent += sent;
    stats.peak_session_bytes = std::max(stats.peak_session_bytes, session_bytes);
  }
};

PvsServer::PvsServer(const World& world, PvsServerOptions options)
    : impl_(std::make_unique<Impl>(world, std::move(options))) {
  Impl& impl = *impl_;
  impl.listener.accept([&impl](tcp::socket socket) {
    impl.open(std::make_shared<net::Connection>(std::move(socket), impl.options.link, impl.options.limits), false);
  });
  if (impl.web) impl.web->accept([&impl](std::shared_ptr<net::Connection> c) { impl.open(std::move(c), true); });
}

PvsServer::~PvsServer() = default;

uint16_t PvsServer::port() const { return impl_->listener.port(); }

uint16_t PvsServer::web_port() const {
  if (!impl_->web) throw Error("this PVS server serves no browsers (PvsServerOptions::web)");
  return impl_->web->port();
}

void PvsServer::run() {
  impl_->io.run();
  if (!impl_->web) return;
  const net::WebListenerStats& w = impl_->web->stats();
  const std::lock_guard lock(impl_->stats_mutex);
  impl_->stats.web_files_served = w.files_served;
  impl_->stats.web_requests_refused = w.refused;
}

void PvsServer::stop() {
  asio::post(impl_->io, [this] {
    impl_->listener.close();
    if (impl_->web) impl_->web->close();
    std::vector<std::shared_ptr<net::Connection>> open;
    for (auto& [id, s] : impl_->sessions) open.push_back(s->connection);
    for (auto& c : open) c->close("the server stopped");
    impl_->io.stop();
  });
}

PvsServerStats PvsServer::stats() const {
  const std::lock_guard lock(impl_->stats_mutex);
  PvsServerStats s = impl_->stats;
  return s;
}

// ---- The blocking client -----------------------------------------------------------------

struct PvsClient::Impl {
  asio::io_context io;
  tcp::socket socket{io};
  net::LinkShaper shaper;
  Welcome welcome;
  std::string where;

  explicit Impl(net::LinkShape outgoing) : shaper(outgoing) {}

  void send(PvsMessage type, std::span<const uint8_t> payload) {
    const std::vector<uint8_t> frame = net::make_frame(uint8_t(type), payload);
    std::this_thread::sleep_until(shaper.arrival(frame.size(), net::Clock::now()));
    boost::system::error_code ec;
    asio::write(socket, asio::buffer(frame), ec);
    if (ec) throw Error(where + ": the server closed the connection (" + ec.message() + ")");
  }

  std::pair<PvsMessage, std::vector<uint8_t>> receive(uint64_t& bytes) {
    std::array<uint8_t, net::kFrameHeaderBytes> header{};
    boost::system::error_code ec;
    asio::read(socket, asio::buffer(header), ec);
    if (ec) throw Error(where + ": the server closed the connection (" + ec.message() + ")");
    net::FrameHeader h;
    try {
      h = net::parse_frame_header(header, 1u << 30);
    } catch (const net::ProtocolError& e) {
      throw Error(where + ": " + e.what());
    }
    std::vector<uint8_t> payload(h.length);
    asio::read(socket, asio::buffer(payload), ec);
    if (ec) throw Error(where + ": the server closed the connection mid-message (" + ec.message() + ")");
    bytes += header.size() + payload.size();
    if (h.type == uint8_t(PvsMessage::error)) throw Error(where + ": the server refused: " + parse_error(payload));
    return {PvsMessage(h.type), std::move(payload)};
  }
};

PvsClient::PvsClient(const std::string& host, uint16_t port, net::LinkShape outgoing)
    : impl_(std::make_unique<Impl>(outgoing)) {
  impl_->where = host + ":" + std::to_string(port);
  boost::system::error_code ec;
  tcp::resolver resolver(impl_->io);
  const auto endpoints = resolver.resolve(host, std::to_string(port), ec);
  if (!ec) asio::connect(impl_->socket, endpoints, ec);
  if (ec) throw Error(impl_->where + ": cannot connect (" + ec.message() + "); is `cellwalk serve` running there?");
  impl_->socket.set_option(tcp::no_delay(true), ec);
  impl_->send(PvsMessage::hello, encode_hello());
  uint64_t bytes = 0;
  auto [type, payload] = impl_->receive(bytes);
  if (type != PvsMessage::welcome) throw Error(impl_->where + ": the server did not welcome this client");
  try {
    impl_->welcome = parse_welcome(payload);
  } catch (const std::exception& e) {
    throw Error(impl_->where + ": " + e.what());
  }
}

PvsClient::~PvsClient() = default;

const Welcome& PvsClient::welcome() const { return impl_->welcome; }

PvsReply PvsClient::fetch(const FetchRequest& request) {
  impl_->send(PvsMessage::fetch, encode_fetch(request));
  Reply reply;
  for (;;) {
    auto [type, payload] = impl_->receive(reply.bytes);
    try {
      if (type == PvsMessage::rows) {
        reply.rows = parse_rows(payload);
      } else if (type == PvsMessage::object) {
        reply.objects.push_back(parse_object(payload));
      } else if (type == PvsMessage::done) {
        const DoneReply d = parse_done(payload);
        if (d.sequence != request.sequence || d.objects != reply.objects.size())
          throw Error("a reply that does not match its fetch");
        return reply;
      } else {
        throw Error("an unexpected message type " + std::to_string(int(type)));
      }
    } catch (const std::exception& e) {
      throw Error(impl_->where + ": " + e.what());
    }
  }
}

}  // namespace cellwalk::pvs_stream

namespace cellwalk::pvs_stream {

// ---- The world file as the source ---------------------------------------------------------

constexpr size_t kReadsInFlight = 6;

struct PvsFileSource::Impl {
  const World& world;
  visibility::StoredPvs pvs;
  Welcome welcome;
  std::vector<uint8_t> held;
  std::atomic<bool> cancelled{false};

  explicit Impl(const World& w) : world(w), pvs(w), welcome(grid_of(w)), held(w.object_count(), 0) {
    welcome.world_bytes = w.file().pages().size_bytes();
  }

  void check_cancelled() const {
    if (cancelled.load()) fail(world.file().path(), "the fetch was cancelled");
  }
};

PvsFileSource::PvsFileSource(const World& world) : impl_(std::make_unique<Impl>(world)) {}
PvsFileSource::~PvsFileSource() = default;
const Welcome& PvsFileSource::welcome() const { return impl_->welcome; }
void PvsFileSource::cancel() { impl_->cancelled = true; }

PvsReply PvsFileSource::fetch(const FetchRequest& request) {
  Impl& m = *impl_;
  m.check_cancelled();
  const uint64_t before = m.world.file().pages().counters().bytes;
  PvsReply reply;
  PlannedReply plan;
  try {
    plan = plan_reply(m.pvs, m.held, request);
  } catch (const net::ProtocolError& e) {
    fail(m.world.file().path(), e.what());
  }
  reply.rows = std::move(plan.rows);
  // The objects' reads go out kReadsInFlight at a time, as a browser's connections to one host
  // do: over a web server each is a round trip of its own.
  reply.objects.resize(plan.send.size());
  std::atomic<size_t> next{0};
  std::string failure;
  std::mutex failure_mutex;
  const auto reader = [&] {
    for (size_t i = next++; i < plan.send.size(); i = next++) {
      const uint32_t id = plan.send[i];
      const uint32_t level = std::min(request.level, m.world.object(id).lod_count - 1);
      try {
        m.check_cancelled();
        reply.objects[i] = {request.sequence, id, level, m.world.read_level(id, level)};
      } catch (const std::exception& e) {
        const std::lock_guard lock(failure_mutex);
        if (failure.empty()) failure = e.what();
        next = plan.send.size();
      }
    }
  };
  std::vector<std::thread> readers;
  for (size_t t = 1; t < std::min(kReadsInFlight, plan.send.size()); ++t) readers.emplace_back(reader);
  reader();
  for (std::thread& t : readers) t.join();
  if (!failure.empty()) throw Error(failure);
  reply.bytes = m.world.file().pages().counters().bytes - before;
  return reply;
}

}  // namespace cellwalk::pvs_stream
