// `cellwalk bench store` (DESIGN.md "Measuring"). Sources of what is measured:
// HDoV thesis §4.2.4 (DPLRU) and §5.7 (DoV and DoV-Time caches); Li & Chiang 1999 (hybrid
// relevance cache); Garland & Heckbert 1997 via meshoptimizer (the simplify reference).
#include "experiments/store/store_report.hpp"

#include <fcntl.h>
#include <meshoptimizer.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <unordered_map>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/store/buffer_manager.hpp"
#include "cellwalk/core/camera.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/lod/lod.hpp"
#include "cellwalk/store/page_file.hpp"
#include "cellwalk/scene/path_generator.hpp"
#include "cellwalk/core/process_memory.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/store/replacement_policy.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/store/world.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"
#include "experiments/common/bench_world.hpp"
#include "experiments/common/svg_plot.hpp"

namespace cellwalk {
namespace {

using Json = nlohmann::ordered_json;
using bench::Clock;
using bench::csv_cells;
using bench::fixed;
using bench::machine_info;
using bench::seconds_since;
using bench::utc_now;
using bench::write_csv;
namespace fs = std::filesystem;

constexpr size_t kRandomReadBytes = 4096;
constexpr size_t kSequentialChunk = 256 * 1024;
constexpr uint64_t kDecodeCap = 48ull << 20;  // encoded bytes decoded per pass at most
// DPLRU's query cell: the walker's surroundings, about one city lot (10–30 m, thesis §3.3).
constexpr float kQueryCellHalfSide = 10.0f;

// Where measured loops leave a result the compiler must compute (cf. benchmark::DoNotOptimize).
volatile uint64_t g_sink = 0;

template <typename Fn>
double timed(Fn&& fn) {
  const auto start = Clock::now();
  fn();
  return seconds_since(start);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

std::string mib(uint64_t bytes) {
  return fixed(double(bytes) / (1 << 20), 1) + " MiB";
}

// ---- Build in a child process -----------------------------------------------------------------

Json to_json(const BuildReport& r) {
  return {{"objects", r.objects},
          {"triangles", r.triangles},
          {"levels", r.levels},
          {"stored_triangles", r.stored_triangles},
          {"raw_bytes", r.raw_bytes},
          {"geometry_bytes", r.geometry_bytes},
          {"level0_bytes", r.level0_bytes},
          {"file_bytes", r.file_bytes},
          {"seconds", r.seconds},
          {"peak_rss_bytes", r.peak_rss_bytes}};
}

void write_all(int fd, const std::string& text) {
  for (size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // the parent reports the missing report
    done += size_t(n);
  }
}

std::string read_all(int fd) {
  std::string text;
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return text;
    text.append(buf, size_t(n));
  }
}

[[noreturn]] void run_build_child(int fd, const std::string& scene, const std::string& world,
                                  const bench::WorldBuild& build) {
  std::string message;
  int code = 0;
  try {
    message = to_json(bench::build_bench_world(scene, world, build)).dump();
  } catch (const std::exception& e) {
    message = e.what();
    code = 1;
  }
  write_all(fd, message);
  ::_exit(code);  // skips the parent's atexit handlers and static destructors
}

// The build every world of the bench gets: `params.threads` threads, the default levels.
bench::WorldBuild world_build(const StoreBenchParams& params, const std::string& progress_label) {
  return {.params = {.threads = params.threads}, .progress_label = progress_label};
}

// Runs build_world in a forked child so the VmHWM it reports is the build's own, not this
// process's (which holds the bench's other data). The child starts with the pages this process
// has resident at the fork: returned as "baseline_rss_bytes" beside the report.
Json build_in_child(const std::string& scene, const std::string& world, const bench::WorldBuild& build) {
  int fds[2];
  if (::pipe(fds) != 0) fail("bench store: build", std::string("pipe: ") + std::strerror(errno));
  std::fflush(stdout);
  std::fflush(stderr);
  const uint64_t baseline = current_rss_bytes();
  const pid_t pid = ::fork();
  if (pid < 0) fail("bench store: build", std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    ::close(fds[0]);
    run_build_child(fds[1], scene, world, build);
  }
  ::close(fds[1]);
  const std::string message = read_all(fds[0]);
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    fail("bench store: build of " + scene, message.empty() ? "the build process died" : message);
  }
  Json report = Json::parse(message);
  report["baseline_rss_bytes"] = baseline;
  report["threads"] = build.params.threads;
  return report;
}

// ---- Build references: meshopt_simplify once and build_lod_chain, same objects ----------------

// One meshopt_simplify call to half the triangles, as the chain's first level asks it.
size_t simplify_half(const Mesh& mesh) {
  if (mesh.indices.empty()) return 0;
  std::vector<uint32_t> out(mesh.indices.size());
  const size_t target = (mesh.triangle_count() + 1) / 2 * 3;
  float error = 0.0f;
  return meshopt_simplify(out.data(), mesh.indices.data(), mesh.indices.size(),
                          &mesh.positions[0].x, mesh.vertex_count(), sizeof(Vec3), target,
                          std::numeric_limits<float>::max(), 0, &error);
}

struct ReferenceTimes {
  uint64_t triangles = 0;
  double simplify_seconds = 0.0;
  double lod_chain_seconds = 0.0;
};

// Per object, both references back to back (alternating which goes first), so drift in the
// machine's speed affects both alike.
ReferenceTimes time_references(const std::string& scene_file, const LodParams& lod) {
  SceneReader scene(scene_file);
  Progress progress("simplify + lod chain", scene.object_count());
  ReferenceTimes t;
  for (ObjectId id = 0; id < scene.object_count(); ++id) {
    const Object object = scene.read_object(id);
    const auto simplify = [&] { t.simplify_seconds += timed([&] { simplify_half(object.mesh); }); };
    const auto chain = [&] {
      t.lod_chain_seconds += timed([&] { build_lod_chain(object.mesh, lod); });
    };
    if (id % 2) {
      simplify();
      chain();
    } else {
      chain();
      simplify();
    }
    t.triangles += object.mesh.triangle_count();
    progress.update(id + 1);
  }
  progress.finish();
  return t;
}

Json build_section(const Json& build, const ReferenceTimes& ref) {
  const double tris = build["triangles"].get<double>();
  const double build_rate = tris / std::max(build["seconds"].get<double>(), 1e-9);
  const double simplify_rate = double(ref.triangles) / std::max(ref.simplify_seconds, 1e-9);
  const double chain_rate = double(ref.triangles) / std::max(ref.lod_chain_seconds, 1e-9);
  Json out = build;
  out["triangles_per_second"] = build_rate;
  out["simplify_triangles_per_second"] = simplify_rate;
  out["lod_chain_triangles_per_second"] = chain_rate;
  out["build_to_simplify"] = build_rate / simplify_rate;
  out["lod_chain_to_simplify"] = chain_rate / simplify_rate;
  return out;
}

// ---- I/O: the store's read paths against the raw device ---------------------------------------

// The reference: pread(2) with O_DIRECT, nothing else. Falls back to drop-behind like
// FileReadSource where the file system refuses O_DIRECT, so both sides bypass the same way.
class RawFile {
 public:
  explicit RawFile(const std::string& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_DIRECT | O_CLOEXEC);
    AlignedBuffer probe = make_aligned_buffer(kRandomReadBytes);
    if (fd_ >= 0 && ::pread(fd_, probe.get(), kRandomReadBytes, 0) < 0) {
      ::close(fd_);
      fd_ = -1;
    }
    if (fd_ < 0) {
      direct_ = false;
      fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    }
    if (fd_ < 0) fail(path, std::string("cannot open: ") + std::strerror(errno));
  }
  ~RawFile() { ::close(fd_); }
  RawFile(const RawFile&) = delete;
  RawFile& operator=(const RawFile&) = delete;

  // REQUIRES: offset, bytes and dst aligned to 4096 (O_DIRECT).
  void read(uint64_t offset, size_t bytes, std::byte* dst) const {
    for (size_t done = 0; done < bytes;) {
      const ssize_t n = ::pread(fd_, dst + done, bytes - done, off_t(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) fail(path_, "raw read failed at byte " + std::to_string(offset + done));
      done += size_t(n);
    }
    if (!direct_) ::posix_fadvise(fd_, off_t(offset), off_t(bytes), POSIX_FADV_DONTNEED);
  }
  CacheBypass mode() const { return direct_ ? CacheBypass::kDirect : CacheBypass::kDropBehind; }

 private:
  std::string path_;
  int fd_ = -1;
  bool direct_ = true;
};

// One read of `bytes` at `offset` within the geometry section.
using ReadMethod = std::function<void(uint64_t offset, size_t bytes, std::byte* dst)>;

struct IoAccess {
  std::string name;
  size_t bytes = 0;               // per read
  std::vector<uint64_t> offsets;  // within the geometry section, page aligned
};

std::vector<IoAccess> io_accesses(const SectionInfo& geometry, uint32_t page_size,
                                  const StoreBenchParams& params) {
  const uint64_t pages = std::max<uint64_t>(geometry.page_count(page_size), 1);
  IoAccess random{"random 4 KiB", kRandomReadBytes, {}};
  Random rng(7);
  for (uint64_t i = 0; i < params.random_reads; ++i)
    random.offsets.push_back(uint64_t(rng.integer(0, int64_t(pages) - 1)) * page_size);
  // A section smaller than a chunk is read whole each time.
  IoAccess sequential{
      "sequential 256 KiB", std::min<uint64_t>(kSequentialChunk, pages * page_size), {}};
  const uint64_t chunks = pages * page_size / sequential.bytes;
  for (uint64_t i = 0; i * sequential.bytes < params.sequential_bytes; ++i) {
    sequential.offsets.push_back(i % chunks * sequential.bytes);
  }
  return {random, sequential};
}

struct NamedMethod {
  std::string name;
  ReadMethod read;
};

// Method 0 is the reference. Each round runs every method once, the order rotated per round.
Json measure_io(const World& world, const StoreBenchParams& params, Json& rows) {
  const WorldFile& file = world.file();
  const SectionInfo& geometry = file.section("geometry");
  const uint64_t base = geometry.first_page * file.page_size();
  RawFile raw(file.path());
  PageFile& pages = file.pages();
  const size_t page = file.page_size();
  const std::vector<NamedMethod> methods = {
      {"raw pread O_DIRECT",
       [&](uint64_t off, size_t n, std::byte* dst) { raw.read(base + off, n, dst); }},
      {"PageFile", [&](uint64_t off, size_t n,
                       std::byte* dst) { pages.read((base + off) / page, n / page, dst); }},
      {"WorldFile::read",
       [&](uint64_t off, size_t n, std::byte*) {
         // Clipped to the section: WorldFile reads only within it.
         file.read(geometry, off,
                   std::min<uint64_t>(n, geometry.bytes - std::min(off, geometry.bytes)));
       }},
  };
  AlignedBuffer buffer = make_aligned_buffer(kSequentialChunk);
  Json summary = Json::array();
  Progress progress("I/O", uint64_t(params.io_rounds) * 2);
  uint64_t step = 0;
  for (const IoAccess& access : io_accesses(geometry, file.page_size(), params)) {
    std::vector<std::vector<double>> seconds(methods.size());
    for (int round = 0; round < params.io_rounds; ++round) {
      for (size_t k = 0; k < methods.size(); ++k) {
        const size_t m = (k + size_t(round)) % methods.size();
        const double s = timed([&] {
          for (uint64_t off : access.offsets) methods[m].read(off, access.bytes, buffer.get());
        });
        seconds[m].push_back(s);
        rows.push_back({access.name, methods[m].name, round, s, access.offsets.size(),
                        access.offsets.size() * access.bytes});
      }
      progress.update(++step);
    }
    for (size_t m = 0; m < methods.size(); ++m) {
      std::vector<double> ratios;  // of throughputs, round by round: raw time / method time
      for (int r = 0; r < params.io_rounds; ++r) ratios.push_back(seconds[0][r] / seconds[m][r]);
      const double t = median(seconds[m]);
      const double ops = double(access.offsets.size());
      summary.push_back({{"access", access.name},
                         {"method", methods[m].name},
                         {"median_seconds", t},
                         {"microseconds_per_read", t / ops * 1e6},
                         {"mb_per_second", ops * double(access.bytes) / t / 1e6},
                         {"throughput_to_raw", median(ratios)}});
    }
  }
  progress.finish();
  return {{"raw_mode", to_string(raw.mode())},
          {"store_mode", to_string(pages.bypass_mode())},
          {"file_bytes", pages.size_bytes()},
          {"results", summary}};
}

// ---- Decode: decode_mesh on the world's encoded levels against memcpy ------------------------

std::vector<std::vector<uint8_t>> encoded_levels(const World& world) {
  std::vector<std::vector<uint8_t>> levels;
  uint64_t bytes = 0;
  for (ObjectId id = 0; id < world.object_count() && bytes < kDecodeCap; ++id) {
    for (uint32_t l = 0; l < world.object(id).lod_count; ++l) {
      levels.push_back(world.read_level(id, l));
      bytes += levels.back().size();
    }
  }
  return levels;
}

// memcpy moves each level's decoded size through fresh memory (buffers the size of all levels),
// so neither side runs from the CPU cache alone.
Json measure_decode(const World& world, const StoreBenchParams& params, Json& rows) {
  const std::vector<std::vector<uint8_t>> levels = encoded_levels(world);
  std::vector<size_t> sizes;
  uint64_t encoded = 0, decoded = 0;
  for (const auto& bytes : levels) {  // also the warm-up
    sizes.push_back(decode_mesh(bytes, "bench store: decode").byte_size());
    encoded += bytes.size();
    decoded += sizes.back();
  }
  std::vector<std::byte> src(decoded, std::byte{1}), dst(decoded);
  uint64_t checksum = 0;  // of what memcpy wrote, left in g_sink so the copies cannot be elided
  std::vector<double> decode_s, memcpy_s, ratios;
  Progress progress("decode", uint64_t(params.io_rounds));
  for (int round = 0; round < params.io_rounds; ++round) {
    const auto decode_pass = [&] {
      decode_s.push_back(timed([&] {
        for (const auto& bytes : levels)
          checksum += decode_mesh(bytes, "bench store: decode").indices.size();
      }));
    };
    const auto copy_pass = [&] {
      memcpy_s.push_back(timed([&] {
        size_t at = 0;
        for (size_t n : sizes) {
          std::memcpy(dst.data() + at, src.data() + at, n);
          checksum += uint64_t(dst[at]);
          at += n;
        }
      }));
    };
    if (round % 2) {
      decode_pass();
      copy_pass();
    } else {
      copy_pass();
      decode_pass();
    }
    ratios.push_back(memcpy_s.back() / decode_s.back());
    rows.push_back({round, levels.size(), encoded, decoded, decode_s.back(), memcpy_s.back()});
    progress.update(uint64_t(round) + 1);
  }
  progress.finish();
  g_sink = checksum;
  return {{"levels", levels.size()},
          {"encoded_bytes", encoded},
          {"decoded_bytes", decoded},
          {"decode_gb_per_second", double(decoded) / median(decode_s) / 1e9},
          {"memcpy_gb_per_second", double(decoded) / median(memcpy_s) / 1e9},
          {"decode_to_memcpy", median(ratios)}};
}

// ---- Cache: one recorded trace replayed through every policy and budget ----------------------

struct TraceAccess {
  CacheKey key = 0;
  EntryMeta meta;
};
struct TraceFrame {
  QueryContext context;
  std::vector<TraceAccess> accesses;
};

// The solid angle of the object's bounding sphere seen from `eye` (2π when inside it): the
// projected-size proxy standing in for the DoV (thesis §5.7) and Li–Chiang relevance.
float solid_angle(const Aabb& box, const Vec3& eye) {
  const float r = 0.5f * glm::length(box.size());
  const float d = glm::length(box.center() - eye);
  if (d <= r) return 2.0f * std::numbers::pi_v<float>;
  const float s = r / d;
  return 2.0f * std::numbers::pi_v<float> * (1.0f - std::sqrt(1.0f - s * s));
}

BlockBox block_box(const Aabb& box) {
  return {{box.min.x, box.min.y, box.min.z}, {box.max.x, box.max.y, box.max.z}};
}

// What the brute-force strategy (src/systems/brute/brute.cpp) asks the store for on each frame of a
// generated walk: level 0 of every object whose bounds meet the frustum, in id order.
std::vector<TraceFrame> record_trace(const World& world, int frames) {
  PathParams path_params;
  path_params.frames = frames;
  const CameraPath path = generate_path(world.info().nav, path_params);
  std::vector<TraceFrame> trace;
  Camera camera;
  for (size_t f = 0; f < path.frames.size(); ++f) {
    apply(path.frames[f], camera);
    const Frustum frustum(camera);
    TraceFrame frame;
    const Vec3 half(kQueryCellHalfSide);
    frame.context = {block_box({camera.position - half, camera.position + half}), f};
    for (ObjectId id = 0; id < world.object_count(); ++id) {
      const Aabb& bounds = world.object(id).bounds;
      if (!frustum.intersects(bounds)) continue;
      const float proxy = solid_angle(bounds, camera.position);
      frame.accesses.push_back(
          {GeometryStore::key(id, 0), EntryMeta{0, block_box(bounds), proxy, proxy, f}});
    }
    trace.push_back(std::move(frame));
  }
  return trace;
}

// Decoded bytes of every object the trace asks for: what each item costs the budget.
std::unordered_map<CacheKey, uint64_t> item_sizes(const World& world,
                                                  const std::vector<TraceFrame>& trace) {
  std::unordered_map<CacheKey, uint64_t> sizes;
  for (const TraceFrame& frame : trace) {
    for (const TraceAccess& a : frame.accesses) sizes.emplace(a.key, 0);
  }
  Progress progress("item sizes", sizes.size());
  uint64_t done = 0;
  for (auto& [key, bytes] : sizes) {
    const ObjectId id = GeometryStore::object_of(key);
    bytes = world.decode_level(id, 0, world.read_level(id, 0)).byte_size();
    progress.update(++done);
  }
  progress.finish();
  return sizes;
}

struct PolicyMaker {
  const char* name;
  std::function<std::unique_ptr<ReplacementPolicy>()> make;
};

std::vector<PolicyMaker> policies() {
  return {{"LRU", [] { return make_lru_policy(); }},
          {"DPLRU", [] { return make_distance_priority_lru_policy(); }},
          {"DoV", [] { return make_dov_policy(); }},
          {"DoV-Time", [] { return make_dov_time_policy(); }},
          {"Hybrid relevance", [] { return make_hybrid_relevance_policy(); }}};
}

struct Replay {
  uint64_t accesses = 0;
  BufferCounters counters;
};

// The handle is dropped at once, as a renderer does after upload: nothing stays in use.
Replay replay(const std::vector<TraceFrame>& trace,
              const std::unordered_map<CacheKey, uint64_t>& sizes, const PolicyMaker& policy,
              uint64_t budget_bytes) {
  MemoryBudget budget(std::max<uint64_t>(budget_bytes, 1));  // 0 would mean unlimited
  BufferManager cache(budget, policy.make());
  Replay r;
  for (const TraceFrame& frame : trace) {
    cache.begin_query(frame.context);
    for (const TraceAccess& a : frame.accesses) {
      const uint64_t bytes = sizes.at(a.key);
      cache.get(a.key, a.meta, [bytes] { return LoadedItem{std::make_shared<char>(), bytes}; });
      ++r.accesses;
    }
  }
  r.counters = cache.counters();
  return r;
}

Json measure_cache(const World& world, const StoreBenchParams& params, Json& rows) {
  const std::vector<TraceFrame> trace = record_trace(world, params.path_frames);
  const std::unordered_map<CacheKey, uint64_t> sizes = item_sizes(world, trace);
  uint64_t working_set = 0, largest = 0, accesses = 0;
  for (const auto& [key, bytes] : sizes) {
    working_set += bytes;
    largest = std::max(largest, bytes);
  }
  uint64_t frame_bytes = 0;  // summed over frames: bytes each frame asks for
  for (const TraceFrame& frame : trace) {
    accesses += frame.accesses.size();
    for (const TraceAccess& a : frame.accesses) frame_bytes += sizes.at(a.key);
  }
  const std::vector<PolicyMaker> makers = policies();
  Progress progress("cache replay", makers.size() * params.budget_fractions.size());
  uint64_t step = 0;
  Json results = Json::array();
  for (const PolicyMaker& policy : makers) {
    for (double fraction : params.budget_fractions) {
      const auto budget = uint64_t(std::ceil(fraction * double(working_set)));
      const Replay r = replay(trace, sizes, policy, budget);
      const double hit_ratio = double(r.counters.hits) / double(std::max<uint64_t>(r.accesses, 1));
      results.push_back({{"policy", policy.name},
                         {"budget_fraction", fraction},
                         {"budget_bytes", budget},
                         {"hit_ratio", hit_ratio},
                         {"bytes_loaded", r.counters.bytes_loaded},
                         {"evictions", r.counters.evictions},
                         {"transient", r.counters.transient}});
      rows.push_back({policy.name, fraction, budget, r.accesses, r.counters.hits, hit_ratio,
                      r.counters.bytes_loaded, r.counters.evictions, r.counters.transient});
      progress.update(++step);
    }
  }
  progress.finish();
  // Every item fits at a budget of the whole working set: only first requests miss.
  const double compulsory = 1.0 - double(sizes.size()) / double(std::max<uint64_t>(accesses, 1));
  return {{"frames", trace.size()},
          {"accesses", accesses},
          {"distinct_items", sizes.size()},
          {"working_set_bytes", working_set},
          {"largest_item_bytes", largest},
          {"hit_ratio_bound", compulsory},
          {"frame_share", double(frame_bytes) / double(std::max<size_t>(trace.size(), 1)) /
                              double(std::max<uint64_t>(working_set, 1))},
          {"results", results}};
}

// ---- The ~10^8-triangle city -------------------------------------------------------------------

// Seconds the large build should take at the rate the small build ran (same city generator and
// landmark fraction, so the same triangles per object on average).
double large_estimate_seconds(const Json& build, uint64_t large_objects) {
  const double per_object =
      build["triangles"].get<double>() / std::max(build["objects"].get<double>(), 1.0);
  return per_object * double(large_objects) /
         std::max(build["triangles_per_second"].get<double>(), 1e-9);
}

Json measure_large(const StoreBenchParams& params, const fs::path& work, const Json& build) {
  const std::string scene = (work / "large.cwscene").string(),
                    world = (work / "large.cww").string();
  std::fprintf(stderr, "bench store: large city of %llu objects, build estimated at %.0f s\n",
               static_cast<unsigned long long>(params.large_objects),
               large_estimate_seconds(build, params.large_objects));
  bench::write_generated_scene(CityParams{.objects = params.large_objects}, scene, "generate city");
  Json report = build_in_child(scene, world, world_build(params, "build large city"));
  report["triangles_per_second"] =
      report["triangles"].get<double>() / std::max(report["seconds"].get<double>(), 1e-9);
  fs::remove(scene);
  fs::remove(world);
  return report;
}

// ---- Report files ------------------------------------------------------------------------------

LinePlot hit_ratio_plot(const Json& cache) {
  LinePlot plot;
  plot.title = "Hit ratio on one frustum-culling walk (" +
               std::to_string(cache["frames"].get<int>()) + " frames)";
  plot.x_label = "budget, fraction of the trace's working set (log)";
  plot.y_label = "hit ratio";
  plot.log_x = true;
  plot.y_min = 0.0;
  plot.y_max = 1.0;
  for (const PolicyMaker& policy : policies()) {
    PlotSeries series{policy.name, {}};
    for (const Json& r : cache["results"]) {
      if (r["policy"] == policy.name)
        series.points.push_back({r["budget_fraction"], r["hit_ratio"]});
    }
    plot.series.push_back(std::move(series));
  }
  return plot;
}

double hit_ratio_of(const Json& cache, const std::string& policy, double fraction) {
  for (const Json& r : cache["results"]) {
    if (r["policy"] == policy && r["budget_fraction"] == fraction) return r["hit_ratio"];
  }
  return 0.0;
}

double io_ratio(const Json& io, const std::string& access, const std::string& method) {
  for (const Json& r : io["results"]) {
    if (r["access"] == access && r["method"] == method) return r["throughput_to_raw"];
  }
  return 0.0;
}

// Where the policies differ most: the budget with the widest spread of hit ratios.
std::string cache_reading(const Json& cache, const Json& fractions) {
  double widest = -1.0, at = fractions.front();
  for (double f : fractions) {
    double lo = 1.0, hi = 0.0;
    for (const PolicyMaker& p : policies()) {
      lo = std::min(lo, hit_ratio_of(cache, p.name, f));
      hi = std::max(hi, hit_ratio_of(cache, p.name, f));
    }
    if (hi - lo > widest) widest = hi - lo, at = f;
  }
  std::string best, ranking;
  double best_ratio = -1.0;
  for (const PolicyMaker& p : policies()) {
    const double h = hit_ratio_of(cache, p.name, at);
    ranking += std::string(ranking.empty() ? "" : ", ") + p.name + " " + fixed(h, 3);
    if (h > best_ratio) best_ratio = h, best = p.name;
  }
  return "Each frame asks for " + fixed(cache["frame_share"].get<double>() * 100, 0) +
         " % of the trace's working set on average, in the same order every frame. The policies "
         "differ most at a budget of " +
         fixed(at * 100, 0) + " % of the working set, where " + best + " hits most (" + ranking +
         "); with the whole working set every policy meets the bound of first-request misses, " +
         fixed(cache["hit_ratio_bound"].get<double>(), 3) + ".";
}

// Sentences computed from the figures, so a regenerated report reads true.
std::vector<std::string> reading(const Json& s) {
  const Json &b = s["build"], &io = s["io"], &d = s["decode"], &c = s["cache"];
  std::vector<std::string> out;
  out.push_back(
      "build_world makes a finished world (every level, encoded, paged, checksummed) at " +
      fixed(b["build_to_simplify"].get<double>(), 2) +
      "× the rate of one meshopt_simplify pass to 1/2 on the same objects (" +
      fixed(b["lod_chain_to_simplify"].get<double>(), 2) +
      "× for build_lod_chain alone), with a peak RSS of " + mib(b["peak_rss_bytes"]) + " for " +
      fixed(b["triangles"].get<double>() / 1e6, 2) + " M triangles.");
  out.push_back("Random 4 KiB reads run at " + fixed(io_ratio(io, "random 4 KiB", "PageFile"), 2) +
                "× the raw O_DIRECT rate through PageFile and " +
                fixed(io_ratio(io, "random 4 KiB", "WorldFile::read"), 2) +
                "× through WorldFile::read (checksums verified); sequential 256 KiB reads at " +
                fixed(io_ratio(io, "sequential 256 KiB", "PageFile"), 2) + "× and " +
                fixed(io_ratio(io, "sequential 256 KiB", "WorldFile::read"), 2) + "×.");
  out.push_back("decode_mesh delivers " + fixed(d["decode_gb_per_second"].get<double>(), 2) +
                " GB/s of decoded mesh, " + fixed(d["decode_to_memcpy"].get<double>(), 3) +
                "× memcpy of the same bytes.");
  out.push_back(cache_reading(c, s["params"]["budget_fractions"]));
  return out;
}

// The store's tables are figures: names left, numbers right.
std::string figures_table(const std::vector<std::string>& header, const bench::Table& rows) {
  return bench::md_table(header, rows, bench::Align::kFigures);
}

std::string header_markdown(const Json& s) {
  const Json& m = s["machine"];
  return "# Store benchmarks\n\nGenerated " + s["date"].get<std::string>() + " by `" +
         s["command"].get<std::string>() + "` on " + m["cpu"].get<std::string>() + ", " +
         std::to_string(m["nproc"].get<int>()) + " cores, " +
         fixed(m["memory_bytes"].get<double>() / double(1ull << 30), 1) + " GiB, load average " +
         fixed(m["load_average"].get<double>(), 1) +
         " at the start. Run the same command to regenerate this page and the CSV/JSON/SVG in "
         "`store/`. "
         "Timings are ratios measured side by side in this run (DESIGN.md \"Measuring\"); absolute "
         "times vary with the machine.\n\n";
}

std::string build_markdown(const Json& b) {
  std::string md = "## Build\n\nA generated city (`generate_city`, " +
                   std::to_string(b["objects"].get<uint64_t>()) + " objects, " +
                   fixed(b["triangles"].get<double>() / 1e6, 2) +
                   " M triangles) built by `build_world` with " + std::to_string(b["threads"].get<int>()) +
                   " thread(s) in a child process, whose VmHWM is the peak below. The references run on the "
                   "same "
                   "objects, read from the same scene file, one thread: `meshopt_simplify` once to 1/2 and "
                   "`build_lod_chain` (every level, no encoding).\n\n";
  md += figures_table(
      {"Stage", "M triangles/s", "× meshopt_simplify"},
      {{"meshopt_simplify once to 1/2",
        fixed(b["simplify_triangles_per_second"].get<double>() / 1e6, 3), "1.000"},
       {"build_lod_chain", fixed(b["lod_chain_triangles_per_second"].get<double>() / 1e6, 3),
        fixed(b["lod_chain_to_simplify"].get<double>(), 3)},
       {"build_world", fixed(b["triangles_per_second"].get<double>() / 1e6, 3),
        fixed(b["build_to_simplify"].get<double>(), 3)}});
  md += "\nPeak RSS of the build " + mib(b["peak_rss_bytes"]) + " (of which " +
        mib(b["baseline_rss_bytes"]) + " inherited from the bench at the fork); " +
        std::to_string(b["levels"].get<uint64_t>()) + " levels, " +
        fixed(b["level0_bytes"].get<double>() / b["triangles"].get<double>(), 2) +
        " bytes/triangle at level 0, file " + mib(b["file_bytes"]) + ".\n\n";
  return md;
}

std::string large_markdown(const Json& large) {
  std::string md = "## A 10^8-triangle city\n\n";
  if (!large.value("run", true))
    return md + "Not run in this report (add `--large`: generates a " +
           std::to_string(large["objects"].get<uint64_t>()) +
           "-object city and builds it in a child process). At the build rate measured above it "
           "would take about " +
           fixed(large["estimated_seconds"].get<double>() / 60, 0) + " minutes.\n\n";
  md += figures_table({"Objects", "Triangles", "Build time", "M triangles/s", "Peak RSS"},
                      {{std::to_string(large["objects"].get<uint64_t>()),
                        fixed(large["triangles"].get<double>() / 1e6, 1) + " M",
                        fixed(large["seconds"].get<double>(), 0) + " s",
                        fixed(large["triangles_per_second"].get<double>() / 1e6, 3),
                        mib(large["peak_rss_bytes"])}});
  return md + "\nTarget: under 2 GiB peak RSS.\n\n";
}

std::string reads_markdown(const Json& io, int rounds) {
  std::string md = "## Reads\n\nThe world's geometry section, page cache bypassed (store: " +
                   io["store_mode"].get<std::string>() + ", reference: " + io["raw_mode"].get<std::string>() +
                   "), " + std::to_string(rounds) +
                   " interleaved rounds; the ratio is the median over rounds of raw time / method time (1 = "
                   "as fast as the device path).\n\n";
  bench::Table rows;
  for (const Json& r : io["results"]) {
    rows.push_back({r["access"], r["method"], fixed(r["microseconds_per_read"].get<double>(), 1),
                    fixed(r["mb_per_second"].get<double>(), 1),
                    fixed(r["throughput_to_raw"].get<double>(), 3)});
  }
  return md + figures_table({"Access", "Method", "µs/read", "MB/s", "× raw"}, rows);
}

std::string decode_markdown(const Json& d) {
  return "\n## Decode\n\n`decode_mesh` on " + std::to_string(d["levels"].get<uint64_t>()) +
         " encoded levels of the world (" + mib(d["encoded_bytes"]) + " encoded, " +
         mib(d["decoded_bytes"]) + " decoded) against memcpy of the decoded bytes.\n\n" +
         figures_table({"", "GB/s of decoded mesh", "× memcpy"},
                       {{"memcpy", fixed(d["memcpy_gb_per_second"].get<double>(), 2), "1.000"},
                        {"decode_mesh", fixed(d["decode_gb_per_second"].get<double>(), 2),
                         fixed(d["decode_to_memcpy"].get<double>(), 3)}});
}

std::string cache_markdown(const Json& c, const Json& fractions) {
  std::string md =
      "\n## Cache policies\n\nOne trace, replayed through a BufferManager under a MemoryBudget per "
      "policy and budget: "
      "a generated walk of " +
      std::to_string(c["frames"].get<int>()) +
      " frames where each frame requests level 0 of every object in the frustum (the brute-force "
      "strategy), " +
      std::to_string(c["accesses"].get<uint64_t>()) + " requests of " +
      std::to_string(c["distinct_items"].get<uint64_t>()) + " items, working set " +
      mib(c["working_set_bytes"]) +
      " of decoded meshes. DoV and relevance are the solid angle of the object's bounding sphere; "
      "DPLRU's query cell "
      "is a 20 m box around the eye. Policies: LRU; DPLRU (HDoV thesis §4.2.4); DoV and DoV-Time "
      "(thesis §5.7); "
      "Li–Chiang hybrid relevance. Brute force asks for the objects in id order every frame: a "
      "cyclic pattern, on "
      "which LRU evicts just the object needed next once the budget is below what one frame asks "
      "for.\n\n";
  std::vector<std::string> header = {"Budget (of working set)"};
  for (const PolicyMaker& p : policies()) header.push_back(p.name);
  bench::Table rows;
  for (double f : fractions) {
    rows.push_back({fixed(f * 100, 0) + " %"});
    for (const PolicyMaker& p : policies())
      rows.back().push_back(fixed(hit_ratio_of(c, p.name, f), 3));
  }
  return md + figures_table(header, rows) + "\n![Hit ratio against budget](store/hit_ratio.svg)\n\n";
}

std::string markdown(const Json& s) {
  std::string md = header_markdown(s) + build_markdown(s["build"]) + large_markdown(s["large"]) +
                   reads_markdown(s["io"], s["params"]["io_rounds"].get<int>()) + decode_markdown(s["decode"]) +
                   cache_markdown(s["cache"], s["params"]["budget_fractions"]) + "## Reading\n\n";
  for (const Json& line : s["reading"]) md += "- " + line.get<std::string>() + "\n";
  return md;
}

void write_report(const fs::path& out, const Json& summary, const Json& io_rows,
                  const Json& decode_rows, const Json& cache_rows) {
  const fs::path dir = out / "store";
  fs::create_directories(dir);
  const Json& b = summary["build"];
  const Json build_rows =
      Json::array({Json::array({"meshopt_simplify", b["triangles"],
                                b["triangles"].get<double>() / b["simplify_triangles_per_second"].get<double>(),
                                b["simplify_triangles_per_second"], nullptr}),
                   Json::array({"build_lod_chain", b["triangles"],
                                b["triangles"].get<double>() / b["lod_chain_triangles_per_second"].get<double>(),
                                b["lod_chain_triangles_per_second"], nullptr}),
                   Json::array({"build_world", b["triangles"], b["seconds"], b["triangles_per_second"],
                                b["peak_rss_bytes"]})});
  write_csv(dir / "build.csv", {"stage", "triangles", "seconds", "triangles_per_second", "peak_rss_bytes"},
            csv_cells(build_rows));
  write_csv(dir / "io.csv", {"access", "method", "round", "seconds", "reads", "bytes"}, csv_cells(io_rows));
  write_csv(dir / "decode.csv",
            {"round", "levels", "encoded_bytes", "decoded_bytes", "decode_seconds", "memcpy_seconds"},
            csv_cells(decode_rows));
  write_csv(dir / "cache.csv",
            {"policy", "budget_fraction", "budget_bytes", "requests", "hits", "hit_ratio", "bytes_loaded",
             "evictions", "transient"},
            csv_cells(cache_rows));
  write_file_atomically((dir / "summary.json").string(), summary.dump(2) + "\n");
  write_file_atomically((dir / "hit_ratio.svg").string(),
                        render_svg(hit_ratio_plot(summary["cache"])));
  write_file_atomically((out / "store.md").string(), markdown(summary));
}

Json params_json(const StoreBenchParams& p) {
  return {{"objects", p.objects},
          {"large", p.large},
          {"large_objects", p.large_objects},
          {"threads", p.threads},
          {"path_frames", p.path_frames},
          {"io_rounds", p.io_rounds},
          {"random_reads", p.random_reads},
          {"sequential_bytes", p.sequential_bytes},
          {"budget_fractions", p.budget_fractions}};
}

}  // namespace

nlohmann::ordered_json run_store_bench(const StoreBenchParams& params) {
  Json summary = {{"date", utc_now()},
                  {"machine", machine_info()},
                  {"command", params.command_line},
                  {"params", params_json(params)}};
  const bench::WorkDir work(params.work_dir, "store");
  const std::string scene = (work.path() / "city.cwscene").string();
  const std::string world_file = (work.path() / "city.cww").string();
  bench::write_generated_scene(CityParams{.objects = params.objects}, scene, "generate city");
  const bench::WorldBuild world_params = world_build(params, "build");
  // First, while this process holds little that the forked child would inherit.
  const Json build = build_in_child(scene, world_file, world_params);
  const ReferenceTimes references = time_references(scene, world_params.params.lod);

  summary["build"] = build_section(build, references);
  const World world(world_file, WorldFile::Options{.bypass_cache = true});
  Json io_rows = Json::array(), decode_rows = Json::array(), cache_rows = Json::array();
  summary["io"] = measure_io(world, params, io_rows);
  summary["decode"] = measure_decode(world, params, decode_rows);
  summary["cache"] = measure_cache(world, params, cache_rows);
  summary["large"] = params.large
                         ? measure_large(params, work.path(), summary["build"])
                         : Json{{"run", false},
                                {"objects", params.large_objects},
                                {"estimated_seconds",
                                 large_estimate_seconds(summary["build"], params.large_objects)}};
  summary["reading"] = reading(summary);
  write_report(params.out_dir, summary, io_rows, decode_rows, cache_rows);
  return summary;
}

}  // namespace cellwalk
