// Seed 004 (Zheng), §4.1, Fig. 5.4 and §8.2.1 over TCP: the VDR streaming server
// (docs/protocol.md, "VDR streaming"; docs/vdr.md, "Server").
#include "cellwalk/systems/vdr/vdr_server.hpp"

#include <algorithm>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <time.h>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/vdr/selective_mesh.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk::vdr {

namespace asio = boost::asio;
using asio::ip::tcp;

namespace {
// Batches a lockstep client may leave unconfirmed: its span is far below.
constexpr size_t kMaxUnconfirmed = 256;
}  // namespace

VdrWelcome welcome_of(const VdrModel& model) {
  const ProgressiveMesh& pm = model.pm;
  VdrWelcome w;
  w.vsplits = pm.vsplit_count();
  w.bounds = model.bounds;
  w.positions.assign(pm.positions.begin(), pm.positions.begin() + pm.base_vertex_count);
  w.normals.assign(pm.normals.begin(), pm.normals.begin() + pm.base_vertex_count);
  w.indices = pm.base_indices;
  return w;
}

struct VdrServer::Impl {
  struct Session {
    uint64_t id = 0;
    std::shared_ptr<net::Connection> connection;
    std::optional<asio::steady_timer> idle;  // restarted by every message
    std::optional<Traversal> traversal;  // from the hello on
    std::optional<SelectiveMesh> shadow;  // lockstep only
    std::deque<std::pair<uint32_t, uint64_t>> unconfirmed;  // (batch, the shadow's digest after it)
    uint32_t next_sequence = 0;
    uint32_t last_applied = kNoBatch;

    uint64_t byte_size() const {
      uint64_t b = connection->queued_bytes() + unconfirmed.size() * 16;
      if (traversal) b += traversal->byte_size();
      if (shadow) b += shadow->render_bytes() + shadow->aux_bytes();
      return b;
    }
  };

  const VdrModel& model;
  VdrServerOptions options;
  std::vector<uint8_t> welcome;  // encoded once, sent to every session
  asio::io_context io;
  net::Listener listener;
  std::map<uint64_t, std::shared_ptr<Session>> sessions;
  uint64_t next_id = 1;
  mutable std::mutex stats_mutex;
  VdrServerStats stats;
  std::vector<Op> ops;  // reused by every batch: one thread

  Impl(const VdrModel& m, VdrServerOptions o)
      : model(m), options(std::move(o)), listener(io, options.port, options.address) {
    const ProgressiveMesh& pm = model.pm;
    welcome = encode_welcome(welcome_of(model));
    stats.model_bytes = model.dag.byte_size() + pm.positions.size() * 24 + pm.adjusted.size() * 4 + pm.v_p.size() * 16;
  }

  void log(const std::string& line) const {
    if (options.log) options.log(line);
  }

  void open(tcp::socket socket) {
    if (sessions.size() >= options.max_sessions) return refuse(std::move(socket));
    auto s = std::make_shared<Session>();
    s->id = next_id++;
    s->connection = std::make_shared<net::Connection>(std::move(socket), options.link, options.limits);
    s->idle.emplace(io);
    sessions[s->id] = s;
    {
      const std::lock_guard lock(stats_mutex);
      ++stats.sessions_opened;
      stats.sessions_open = sessions.size();
    }
    log("session " + std::to_string(s->id) + " opened");
    std::weak_ptr<Session> weak = s;
    s->connection->start(
        [this, weak](uint8_t type, std::vector<uint8_t> payload) {
          if (auto session = weak.lock()) {
            watch_idle(session);
            handle(*session, type, payload);
          }
        },
        [this, id = s->id](const std::string& reason) { closed(id, reason); });
    watch_idle(s);
  }

  // One session too many: told why, then closed; it never becomes a session.
  void refuse(tcp::socket socket) {
    const std::string why = "the server is full (" + std::to_string(options.max_sessions) + " sessions); try again later";
    auto c = std::make_shared<net::Connection>(std::move(socket), net::LinkShape{}, options.limits);
    c->start([](uint8_t, std::vector<uint8_t>) {}, [](const std::string&) {});
    c->send(uint8_t(VdrMessage::error), encode_error(why));
    c->close_after_sending(why);
    {
      const std::lock_guard lock(stats_mutex);
      ++stats.sessions_refused;
    }
    log("connection refused: " + why);
  }

  // (Re)starts the session's idle timer; when it fires, the session is dropped.
  void watch_idle(const std::shared_ptr<Session>& s) {
    if (options.idle.count() <= 0) return;
    s->idle->expires_after(options.idle);
    s->idle->async_wait([weak = std::weak_ptr<Session>(s), ms = options.idle.count()](const boost::system::error_code& ec) {
      const auto session = weak.lock();
      if (ec || !session) return;
      const std::string why = "sent nothing for " + std::to_string(ms) + " ms";
      session->connection->send(uint8_t(VdrMessage::error), encode_error(why));
      session->connection->close_after_sending(why);
    });
  }

  void closed(uint64_t id, const std::string& reason) {
    const auto it = sessions.find(id);
    if (it == sessions.end()) return;
    // A client that goes away — closing, or resetting with batches unread — is not dropped; a
    // session the server closes for what it sent or failed to send is.
    const bool orderly = reason == "the peer closed the connection" || reason.starts_with("read failed:") ||
                         reason.starts_with("write failed:");
    {
      const std::lock_guard lock(stats_mutex);
      stats.bytes_sent += it->second->connection->bytes_sent();
      if (!orderly) ++stats.sessions_dropped;
    }
    log("session " + std::to_string(id) + (orderly ? " closed" : " dropped: " + reason));
    it->second->idle->cancel();
    asio::post(io, [keep = it->second] {});  // the connection calls this from inside itself
    sessions.erase(it);
    const std::lock_guard lock(stats_mutex);
    stats.sessions_open = sessions.size();
  }

  void handle(Session& s, uint8_t type, const std::vector<uint8_t>& payload) {
    try {
      if (!s.traversal) {
        if (type != uint8_t(VdrMessage::hello)) throw net::ProtocolError("the first message must be hello");
        greet(s, parse_hello(payload));
        return;
      }
      if (type != uint8_t(VdrMessage::view)) throw net::ProtocolError("unexpected message type " + std::to_string(type));
      answer(s, parse_view(payload));
    } catch (const std::exception& e) {
      s.connection->send(uint8_t(VdrMessage::error), encode_error(e.what()));
      s.connection->close_after_sending(e.what());
    }
  }

  void greet(Session& s, const Hello& hello) {
    s.traversal.emplace(model, hello.kind, hello.units);
    if (hello.lockstep) {
      const ProgressiveMesh& pm = model.pm;
      s.shadow.emplace(std::span(pm.positions).first(pm.base_vertex_count), std::span(pm.normals).first(pm.base_vertex_count),
                       pm.base_indices);
    }
    s.connection->send(uint8_t(VdrMessage::welcome), welcome);
  }

  // Lockstep (docs/protocol.md): the client's digest after batch `applied` must be the shadow's.
  void confirm(Session& s, const ViewRequest& v) {
    if (v.applied == kNoBatch) return;
    if ((s.last_applied != kNoBatch && v.applied < s.last_applied) || v.applied >= s.next_sequence)
      throw net::ProtocolError("the client says it applied batch " + std::to_string(v.applied) + ", which is out of order");
    s.last_applied = v.applied;
    if (!s.shadow) return;
    while (!s.unconfirmed.empty() && s.unconfirmed.front().first < v.applied) s.unconfirmed.pop_front();
    if (s.unconfirmed.empty() || s.unconfirmed.front().first != v.applied) return;  // confirmed before
    if (s.unconfirmed.front().second != v.digest)
      throw net::ProtocolError("lockstep lost: after batch " + std::to_string(v.applied) +
                               " the client's mesh differs from the server's shadow");
  }

  // Fig. 5.4's loop body: one request, one batch.
  void answer(Session& s, const ViewRequest& v) {
    if (v.sequence != s.next_sequence)
      throw net::ProtocolError("request " + std::to_string(v.sequence) + " where " + std::to_string(s.next_sequence) + " was due");
    confirm(s, v);
    const Stopwatch watch;
    ops.clear();
    s.traversal->manage(v.view, ops, kMaxBatchBytes - kBatchHeaderBytes);
    std::vector<WireOp> wire;
    wire.reserve(ops.size());
    for (const Op& op : ops) wire.push_back(wire_op(model.pm, op));
    const std::vector<uint8_t> batch = encode_batch(v.sequence, s.traversal->triangle_count(), wire);
    const double ms = watch.ms();
    if (s.shadow) {
      for (const WireOp& op : wire) op.split ? s.shadow->vsplit(vsplit_op(op)) : s.shadow->ecol(vsplit_op(op));
      s.unconfirmed.emplace_back(v.sequence, mesh_digest(*s.shadow));
      if (s.unconfirmed.size() > kMaxUnconfirmed)
        throw net::ProtocolError("more than " + std::to_string(kMaxUnconfirmed) + " batches the client never confirmed");
    }
    ++s.next_sequence;
    s.connection->send(uint8_t(VdrMessage::batch), batch);
    account(s, ops.size(), ms);
  }

  void account(const Session& s, size_t op_count, double ms) {
    uint64_t all = 0;
    for (const auto& [id, other] : sessions) all += other->byte_size();
    const std::lock_guard lock(stats_mutex);
    ++stats.batches;
    stats.ops += op_count;
    stats.traversal_ms += ms;
    stats.peak_session_bytes = std::max(stats.peak_session_bytes, all);
    stats.peak_one_session_bytes = std::max(stats.peak_one_session_bytes, s.byte_size());
  }
};

VdrServer::VdrServer(const VdrModel& model, VdrServerOptions options)
    : impl_(std::make_unique<Impl>(model, std::move(options))) {
  impl_->listener.accept([this](tcp::socket socket) { impl_->open(std::move(socket)); });
}

VdrServer::~VdrServer() = default;

uint16_t VdrServer::port() const { return impl_->listener.port(); }

void VdrServer::run() {
  const auto thread_cpu_ms = [] {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) * 1e3 + double(t.tv_nsec) / 1e6;
  };
  const double start = thread_cpu_ms();
  impl_->io.run();
  const std::lock_guard lock(impl_->stats_mutex);
  impl_->stats.cpu_ms += thread_cpu_ms() - start;
}

void VdrServer::stop() {
  asio::post(impl_->io, [this] {
    impl_->listener.close();
    std::vector<std::shared_ptr<net::Connection>> open;
    for (auto& [id, s] : impl_->sessions) open.push_back(s->connection);
    for (auto& c : open) c->close("the server stopped");
    impl_->io.stop();
  });
}

VdrServerStats VdrServer::stats() const {
  const std::lock_guard lock(impl_->stats_mutex);
  return impl_->stats;
}

}  // namespace cellwalk::vdr
