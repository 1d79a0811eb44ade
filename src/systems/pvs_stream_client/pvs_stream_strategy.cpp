// Seed 004 (Zheng), ch. 7: §7.2 SNP and PBNP prefetch, §7.3 delta transmission, §7.4 the
// client's cache, as a strategy over a real socket; the speed-aware prefetch of §7.6's future
// work with the digest's region size (§3.10 gaps: speed × transaction time).
#include "cellwalk/systems/pvs_stream_client/pvs_stream_strategy.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <tuple>
#include <unordered_map>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/http_read_source.hpp"
#include "cellwalk/systems/pvs_stream/pvs_cache.hpp"
#include "cellwalk/systems/pvs_stream/pvs_server.hpp"
#include "core/stopwatch.hpp"
#include "strategy/strategy_config.hpp"

namespace cellwalk {

using namespace pvs_stream;

bool is_pvs_stream_strategy_name(const std::string& name) { return strategy_base(name) == "pvs-stream"; }

PvsStreamConfig parse_pvs_stream_strategy_name(const std::string& name) {
  if (!is_pvs_stream_strategy_name(name))
    fail("strategy \"" + name + "\"", "not a PVS streaming name (pvs-stream[:key=value,...])");
  PvsStreamConfig c;
  bool band_given = false, link_given = false;
  for_each_strategy_setting(name, [&](const StrategySetting& s) {
    if (s.key == "prefetch") {
      s.choice({"snp", "pbnp", "speed"});
      c.prefetch = s.value == "snp" ? PvsStreamConfig::Prefetch::kSnp
                   : s.value == "pbnp" ? PvsStreamConfig::Prefetch::kPbnp : PvsStreamConfig::Prefetch::kSpeed;
    } else if (s.key == "band") {
      c.band = s.number(0.01, 0.45);
      band_given = true;
    } else if (s.key == "server" && is_http_url(s.value)) {
      try {  // a bad URL is refused with the name, not at the first fetch
        parse_http_url(s.value);
      } catch (const Error& e) {
        fail("strategy \"" + name + "\"", e.what());
      }
      c.url = s.value;
    } else if (s.key == "server") {
      std::tie(c.host, c.port) =
          s.host_port("HOST:PORT (e.g. server=127.0.0.1:7878) or the world's URL on a web server (http://HOST:PORT/PATH.cww)");
    } else if (s.key == "latency_ms") {
      c.latency_ms = s.number(0, 10000);
      link_given = true;
    } else if (s.key == "bandwidth_mbit") {
      c.bandwidth_mbit = s.number(0, 1e6);
      link_given = true;
    } else if (s.key == "wait_ms") c.wait_ms = s.number(0, 600000);
    else if (s.key == "pace") c.pace = s.whole(0, 1) != 0;
    else if (s.key == "entries") c.entries = s.whole(1, 1000);
    else if (s.key == "level") c.level = uint32_t(s.whole(0, 255));
    else s.unknown("prefetch, band, server, latency_ms, bandwidth_mbit, wait_ms, pace, entries, level");
  });
  // Speed-aware: the band grows with speed from a small floor (a slow viewer asks late and rarely).
  if (c.prefetch == PvsStreamConfig::Prefetch::kSpeed && !band_given) c.band = 0.05;
  if (c.prefetch == PvsStreamConfig::Prefetch::kSnp && band_given)
    fail("strategy \"" + name + "\"", "band sets PBNP's regions; snp prefetches on cell changes and has none");
  if (!c.url.empty() && !c.host.empty()) fail("strategy \"" + name + "\"", "give one server=");
  if (!c.host.empty() && link_given)
    fail("strategy \"" + name + "\"", "latency_ms and bandwidth_mbit shape the link of the strategy's own server; "
                                      "shape a running server with `cellwalk serve --latency-ms --bandwidth-mbit`");
  const int area = c.prefetch == PvsStreamConfig::Prefetch::kSnp ? 9 : 4;
  if (c.entries < area)
    fail("strategy \"" + name + "\"", "entries=" + std::to_string(c.entries) + " cannot hold a prefetching area of " +
                                          std::to_string(area) + " cells; give entries=" + std::to_string(area) + " or more");
  return c;
}

namespace {

using Clock = std::chrono::steady_clock;

// One object the client holds: the level the server sent, decoded.
struct Held {
  std::shared_ptr<const Mesh> mesh;
  uint32_t level = 0;
  uint64_t bytes = 0;
};

}  // namespace

struct PvsStreamStrategy::Impl {
  const World& world;
  const PvsStreamConfig config;
  const StrategyOptions options;
  std::unique_ptr<PvsServer> server;  // the strategy's own (config.host empty)
  std::thread server_thread;
  std::unique_ptr<World> remote;     // the world behind a web server (config.url)
  std::unique_ptr<PvsSource> source;
  Welcome welcome;
  std::optional<ViewcellGrid> grid;
  std::unordered_map<uint32_t, uint32_t> grid_index_of_cell;  // cell id → row * cols + col
  std::thread network;

  // Shared between the frames and the network thread: under `mutex`.
  mutable std::mutex mutex;
  std::condition_variable changed;
  bool stopping = false;
  std::string failure;
  GridCell current{};
  std::vector<GridCell> area;       // the latest prefetching area; never replaced
  bool tight = false;               // the budget replaced a row of the area (until the cell changes)
  std::vector<GridCell> cells;      // the rows held, oldest first (the local PVS table)
  std::map<uint32_t, std::vector<uint32_t>> rows;  // grid index → sorted object ids
  std::unordered_map<uint32_t, Held> objects;      // the local graphical database
  std::vector<uint32_t> dropped;    // deleted since the last fetch (§7.4's ΔS_d), named in the next
  uint64_t held_bytes = 0, peak_bytes = 0;
  PvsStreamCounters counters;
  std::vector<double> transaction_times;

  // The frames' own.
  std::optional<GridCell> shown;  // the cell whose row the last frame drew
  std::unordered_map<uint32_t, std::shared_ptr<const Mesh>> pinned;  // this frame's meshes
  std::optional<Clock::time_point> epoch;  // wall time of path time 0 (pace)
  std::optional<std::pair<double, Vec3>> last;  // the last frame's path time and position
  double speed = 0.0;                            // m/s, smoothed
  bool started = false;

  Impl(const World& w, const PvsStreamConfig& c, const StrategyOptions& o) : world(w), config(c), options(o) {}
  ~Impl() { shutdown(); }

  std::string where() const {
    if (!config.url.empty()) return "pvs-stream (" + config.url + ")";
    return "pvs-stream (" + (config.host.empty() ? std::string("its own server") : config.host + ":" + std::to_string(config.port)) + ")";
  }

  // The source of rows and objects: a web server's file, a running server, or the strategy's own.
  void connect() {
    const net::LinkShape link{config.latency_ms, config.bandwidth_mbit};
    if (!config.url.empty()) {
      // One range request is one round trip: both directions' delay, and the bytes at the rate.
      remote = std::make_unique<World>(config.url, WorldFile::Options{.read_latency_us = uint32_t(std::lround(2000.0 * config.latency_ms)),
                                                                      .read_bandwidth_mbit = config.bandwidth_mbit});
      source = std::make_unique<PvsFileSource>(*remote);
      return;
    }
    std::string host = config.host;
    uint16_t port = config.port;
    if (host.empty()) {
      PvsServerOptions so;
      so.link = link;
      server = std::make_unique<PvsServer>(world, so);
      server_thread = std::thread([this] { server->run(); });
      host = "127.0.0.1";
      port = server->port();
    }
    source = std::make_unique<PvsClient>(host, port, config.host.empty() ? link : net::LinkShape{});
  }

  void start() {
    const Welcome local = grid_of(world);  // throws, naming the command, without grid sets
    connect();
    welcome = source->welcome();
    if (welcome.objects != local.objects || welcome.cell_count != local.cell_count || welcome.cells != local.cells)
      fail(where(), "serves another world (" + std::to_string(welcome.objects) + " objects, " +
                        std::to_string(welcome.cell_count) + " cells; this one has " + std::to_string(local.objects) +
                        " and " + std::to_string(local.cell_count) + "); serve " + world.file().path() + " there");
    std::vector<uint8_t> present(welcome.cells.size());
    for (size_t i = 0; i < welcome.cells.size(); ++i) {
      present[i] = welcome.cells[i] != kNoCell;
      if (present[i]) grid_index_of_cell[welcome.cells[i]] = uint32_t(i);
    }
    grid.emplace(int(welcome.rows), int(welcome.cols), welcome.cell_size, std::move(present));
    network = std::thread([this] { run_network(); });
  }

  void shutdown() {
    {
      const std::lock_guard lock(mutex);
      stopping = true;
    }
    changed.notify_all();
    if (server) server->stop();  // ends a fetch in flight: the network thread sees `stopping`
    if (source) source->cancel();
    if (network.joinable()) network.join();
    if (server_thread.joinable()) server_thread.join();
  }

  // REQUIRES: mutex held.
  bool cached(GridCell c) const { return std::find(cells.begin(), cells.end(), c) != cells.end(); }
  // With `tight` only the current cell is asked for: asking again for area rows the budget had
  // to replace would replace them again, a fetch after fetch.
  std::vector<GridCell> missing() const {
    std::vector<GridCell> out;
    for (const GridCell& c : tight ? std::vector<GridCell>{current} : area)
      if (!cached(c)) out.push_back(c);
    return out;
  }
  uint64_t resident() const {
    uint64_t bytes = held_bytes + (remote ? remote->resident_bytes() : 0);
    for (const auto& [index, ids] : rows) bytes += ids.size() * sizeof(uint32_t);
    return bytes;
  }

  // One transaction at a time: the rows of the area not held, with the drops since the last.
  void run_network() {
    uint32_t sequence = 0;
    std::unique_lock lock(mutex);
    for (;;) {
      changed.wait(lock, [&] { return stopping || !missing().empty(); });
      if (stopping) return;
      const std::vector<GridCell> wanted = missing();
      FetchRequest request{++sequence, config.level, {}, std::move(dropped)};
      dropped.clear();
      for (const GridCell& c : wanted) request.cells.push_back(welcome.cells[grid->index(c)]);
      ++counters.transactions;
      lock.unlock();
      const Stopwatch watch;
      PvsReply reply;
      std::vector<Held> decoded;
      std::string error;
      try {
        reply = source->fetch(request);
        decoded = decode(reply);
      } catch (const std::exception& e) {
        error = e.what();
      }
      const double ms = watch.ms();
      lock.lock();
      if (stopping) return;
      if (error.empty()) error = admit(request, reply, std::move(decoded), ms);
      if (!error.empty()) {
        failure = error;
        changed.notify_all();
        return;
      }
      changed.notify_all();
    }
  }

  // The objects of a reply, checked against the world and decoded (off the lock).
  std::vector<Held> decode(const PvsReply& reply) const {
    std::vector<Held> out;
    for (const ObjectReply& o : reply.objects) {
      if (o.id >= world.object_count() || o.level >= world.object(o.id).lod_count)
        fail(where(), "sent object " + std::to_string(o.id) + " level " + std::to_string(o.level) + ", which this world does not have");
      Mesh mesh = world.decode_level(o.id, o.level, o.bytes);
      const uint64_t bytes = mesh.byte_size();
      out.push_back({std::make_shared<const Mesh>(std::move(mesh)), o.level, bytes});
    }
    return out;
  }

  // Takes a reply into the cache and replaces rows as §7.4 says. REQUIRES: mutex held. Returns
  // what is wrong with the reply, or "".
  std::string admit(const FetchRequest& request, const PvsReply& reply, std::vector<Held> decoded, double ms) {
    if (reply.rows.rows.size() != request.cells.size()) return where() + ": a reply whose rows are not the cells asked for";
    for (size_t i = 0; i < reply.objects.size(); ++i) {
      Held& h = objects[reply.objects[i].id];
      held_bytes = held_bytes - h.bytes + decoded[i].bytes;
      h = std::move(decoded[i]);
    }
    for (size_t i = 0; i < reply.rows.rows.size(); ++i) {
      const auto& [cell, ids] = reply.rows.rows[i];
      if (cell != request.cells[i]) return where() + ": a reply whose rows are not the cells asked for";
      for (uint32_t id : ids)
        if (!objects.count(id))
          return where() + ": the row of cell " + std::to_string(cell) + " names object " + std::to_string(id) +
                 ", which the server neither sent nor knows this client holds";
      const GridCell c = grid->cell_of(grid_index_of_cell.at(cell));
      rows[grid->index(c)] = ids;
      cells.push_back(c);
    }
    counters.rows_received += reply.rows.rows.size();
    counters.objects_received += reply.objects.size();
    counters.bytes_received += reply.bytes;
    counters.transaction_ms_sum += ms;
    transaction_times.push_back(ms);
    counters.transaction_ms_max = std::max(counters.transaction_ms_max, ms);
    while (cells.size() > size_t(config.entries)) {
      const size_t victim = replacement_victim(cells, area, current);
      if (victim == cells.size()) break;  // the area alone fills the cache (entries ≥ its size: not reached)
      replace(victim);
    }
    // The budget: rows farther than the current cell go, farthest first; the current cell's own
    // objects must fit. Each row's objects go with it, so the next test sees what is left.
    while (options.memory_budget_bytes && resident() > options.memory_budget_bytes) {
      const size_t victim = replacement_victim(cells, {current}, current);
      if (victim == cells.size())
        return where() + ": the objects visible from the current cell need " + std::to_string(resident() >> 20) +
               " MiB, over the memory budget of " + std::to_string(options.memory_budget_bytes >> 20) + " MiB; raise --budget";
      tight = tight || std::find(area.begin(), area.end(), cells[victim]) != area.end();
      replace(victim);
    }
    peak_bytes = std::max(peak_bytes, resident());
    return "";
  }

  // §7.4: row cells[victim] goes, with the objects no kept row sees (ΔS_d = S_d − S_c).
  // REQUIRES: mutex held.
  void replace(size_t victim) {
    const GridCell gone = cells[victim];
    cells.erase(cells.begin() + ptrdiff_t(victim));
    ++counters.cache_swaps;
    std::vector<const std::vector<uint32_t>*> kept;
    for (const GridCell& c : cells) kept.push_back(&rows.at(grid->index(c)));
    const std::vector<uint32_t> deleted = minus(rows.at(grid->index(gone)), union_of(kept));
    for (uint32_t id : deleted) {
      held_bytes -= objects.at(id).bytes;
      objects.erase(id);
    }
    rows.erase(grid->index(gone));
    dropped.insert(dropped.end(), deleted.begin(), deleted.end());
    counters.objects_dropped += deleted.size();
  }

  // The viewer moves at the path's speed: a frame waits for its path time.
  void pace(double time) {
    if (!config.pace || !epoch) return;
    std::this_thread::sleep_until(*epoch + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(time)));
  }

  // PBNP's band: fixed, or (speed) the fraction of a cell the viewer covers in one transaction
  // time, so it enters the band at least one transaction before it crosses the border.
  double band() {
    if (config.prefetch != PvsStreamConfig::Prefetch::kSpeed) return config.band;
    const double transaction_s = counters.transactions ? counters.transaction_ms_sum / 1000.0 / double(counters.transactions) : 0.0;
    return std::clamp(speed * transaction_s / grid->cell_size(), config.band, 0.45);
  }

  void track_speed(const Camera& camera, double time) {
    if (last && time > last->first) {
      const double dx = camera.position.x - last->second.x, dz = camera.position.z - last->second.z;
      const double v = std::hypot(dx, dz) / (time - last->first);
      speed = speed == 0.0 ? v : 0.8 * speed + 0.2 * v;
    }
    last = {time, camera.position};
  }

  std::optional<GridCell> locate(const Camera& camera) const {
    const GridCell c = grid->cell_at(camera.position.x - welcome.origin_x, camera.position.z - welcome.origin_z);
    if (!grid->contains(c)) return std::nullopt;
    return c;
  }
};

PvsStreamStrategy::PvsStreamStrategy(const World& world, const PvsStreamConfig& config, const StrategyOptions& options)
    : impl_(std::make_unique<Impl>(world, config, options)) {
  impl_->start();  // on a throw, ~Impl stops what started
}

PvsStreamStrategy::~PvsStreamStrategy() = default;

std::string PvsStreamStrategy::name() const {
  const PvsStreamConfig& c = impl_->config;
  return std::string("pvs-stream:") + (c.prefetch == PvsStreamConfig::Prefetch::kSnp ? "snp"
                                       : c.prefetch == PvsStreamConfig::Prefetch::kPbnp ? "pbnp" : "speed");
}

void PvsStreamStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Impl& s = *impl_;
  s.pace(stats.time);
  const Stopwatch watch;
  s.track_speed(camera, stats.time);
  const std::optional<GridCell> here = s.locate(camera);
  const double band = s.band();
  std::unique_lock lock(s.mutex);
  ++s.counters.frames;
  s.counters.band_sum += band;
  if (!s.failure.empty()) throw Error(s.failure);
  if (here) {
    if (s.shown && *here != *s.shown) ++s.counters.cell_crossings;
    const Region region = s.grid->region_at(camera.position.x - s.welcome.origin_x, camera.position.z - s.welcome.origin_z, band);
    const PrefetchAlgorithm algorithm = s.config.prefetch == PvsStreamConfig::Prefetch::kSnp ? PrefetchAlgorithm::snp : PrefetchAlgorithm::pbnp;
    if (*here != s.current) s.tight = false;
    s.current = *here;
    s.area = prefetching_area(algorithm, *s.grid, *here, region);
    s.changed.notify_all();
    if (!s.cached(*here)) {
      const Stopwatch waited;
      // Start-up waits as long as it takes (bounded, so a dead link ends with an error).
      const double limit_ms = s.started ? s.config.wait_ms : std::max(s.config.wait_ms, 60000.0);
      s.changed.wait_for(lock, std::chrono::duration<double, std::milli>(limit_ms),
                         [&] { return s.cached(*here) || !s.failure.empty(); });
      if (!s.failure.empty()) throw Error(s.failure);
      if (!s.started) {
        s.counters.startup_ms = waited.ms();
        if (!s.cached(*here)) fail(s.where(), "sent no visible set in " + std::to_string(int(limit_ms / 1000)) + " s");
      } else {
        ++s.counters.stall_frames;
        stats.stall = true;
        if (!s.cached(*here)) ++s.counters.late_frames;
      }
    }
    if (s.cached(*here)) s.shown = *here;
  }
  s.started = true;
  items.clear();
  s.pinned.clear();
  if (s.shown && s.cached(*s.shown)) {
    const Frustum frustum(camera);
    for (uint32_t id : s.rows.at(s.grid->index(*s.shown))) {
      const ObjectRecord& o = s.world.object(id);
      if (!frustum.intersects(o.bounds)) continue;
      const Held& h = s.objects.at(id);
      items.push_back({id, h.level, o.color});
      s.pinned[id] = h.mesh;
    }
  }
  lock.unlock();
  if (!s.epoch) s.epoch = Clock::now() - std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(stats.time));
  stats.query_ms += watch.ms();
}

const Mesh* PvsStreamStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  const auto it = impl_->pinned.find(item.id);
  if (it == impl_->pinned.end()) return nullptr;
  ++stats.cache_hits;
  return it->second.get();
}

uint64_t PvsStreamStrategy::resident_bytes() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->resident();
}

uint64_t PvsStreamStrategy::peak_resident_bytes() const {
  const std::lock_guard lock(impl_->mutex);
  return std::max(impl_->peak_bytes, impl_->resident());
}

PvsStreamCounters PvsStreamStrategy::counters() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->counters;
}

std::vector<std::pair<std::string, double>> PvsStreamStrategy::walk_counters() const {
  const PvsStreamCounters c = counters();
  return {{"stall_frames", double(c.stall_frames)},
          {"late_frames", double(c.late_frames)},
          {"startup_ms", c.startup_ms},
          {"cell_crossings", double(c.cell_crossings)},
          {"transactions", double(c.transactions)},
          {"transaction_ms_mean", c.transactions ? c.transaction_ms_sum / double(c.transactions) : 0.0},
          {"transaction_ms_max", c.transaction_ms_max},
          {"rows_received", double(c.rows_received)},
          {"rows_replaced", double(c.cache_swaps)},
          {"objects_received", double(c.objects_received)},
          {"objects_dropped", double(c.objects_dropped)},
          {"bytes_received", double(c.bytes_received)}};
}

std::vector<double> PvsStreamStrategy::transaction_times_ms() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->transaction_times;
}

std::optional<uint32_t> PvsStreamStrategy::cell_id(const Camera& camera) const {
  const std::optional<GridCell> c = impl_->locate(camera);
  if (!c) return std::nullopt;
  return impl_->welcome.cells[impl_->grid->index(*c)];
}

}  // namespace cellwalk
