// Store benchmarks (DESIGN.md "Out-of-core for real"; HDoV thesis digest §3.4, §3.11, §5.5;
// seeds/003):
//   1. PageFile random and sequential page reads with the OS page cache bypassed, against a raw
//      pread loop bypassed the same way, on the same 256 MiB file in the same run;
//   2. hit ratio of every replacement policy on one synthetic walkthrough trace (an R-tree-like
//      quadtree searched each frame around a moving viewer) at a range of budgets.
// Run from the build directory (the data file is created there): ./store_bench
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "cellwalk/store/buffer_manager.hpp"
#include "cellwalk/store/page_file.hpp"

namespace cellwalk {
namespace {

constexpr size_t kPage = 4096;
constexpr uint64_t kFileBytes = uint64_t(256) << 20;
constexpr uint64_t kFilePages = kFileBytes / kPage;

const std::string& data_file() {
  static const std::string path = [] {
    const std::string p = (std::filesystem::current_path() / "store_bench.dat").string();
    if (!std::filesystem::exists(p) || std::filesystem::file_size(p) != kFileBytes) {
      std::ofstream out(p, std::ios::binary);
      std::mt19937_64 rng(1);
      std::vector<uint64_t> chunk(1 << 17);
      for (uint64_t written = 0; written < kFileBytes; written += chunk.size() * 8) {
        for (uint64_t& v : chunk) v = rng();
        out.write(reinterpret_cast<const char*>(chunk.data()), chunk.size() * 8);
      }
    }
    return p;
  }();
  return path;
}

// The raw baseline: O_DIRECT pread into an aligned buffer, or buffered pread + DONTNEED, chosen
// the same way PageFile chooses.
struct RawFile {
  int fd = -1;
  bool direct = true;
  RawFile() {
    fd = ::open(data_file().c_str(), O_RDONLY | O_DIRECT);
    if (fd < 0) {
      direct = false;
      fd = ::open(data_file().c_str(), O_RDONLY);
    }
  }
  ~RawFile() { ::close(fd); }
  void read(uint64_t page, uint64_t count, void* dst) const {
    const ssize_t got = ::pread(fd, dst, count * kPage, off_t(page * kPage));
    if (got != ssize_t(count * kPage)) std::abort();
    if (!direct) ::posix_fadvise(fd, off_t(page * kPage), off_t(count * kPage), POSIX_FADV_DONTNEED);
  }
};

// state.range(0) = pages per request; state.range(1) = 1 for random, 0 for sequential.
template <class Reader>
void read_loop(benchmark::State& state, const Reader& reader) {
  const uint64_t count = uint64_t(state.range(0));
  const bool random = state.range(1) != 0;
  AlignedBuffer buffer = make_aligned_buffer(count * kPage);
  std::mt19937_64 rng(7);
  uint64_t next = 0;
  for (auto _ : state) {
    const uint64_t page = random ? rng() % (kFilePages - count) : next;
    next = (next + count) % (kFilePages - count);
    reader(page, count, buffer.get());
    benchmark::DoNotOptimize(buffer.get()[0]);
  }
  state.SetBytesProcessed(int64_t(state.iterations() * count * kPage));
  state.counters["requests/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_PageFileRead(benchmark::State& state) {
  PageFile file(data_file(), {.page_size = kPage, .bypass_cache = true});
  state.SetLabel(to_string(file.bypass_mode()));
  read_loop(state, [&](uint64_t page, uint64_t count, void* dst) { file.read(page, count, dst); });
}

void BM_RawPread(benchmark::State& state) {
  RawFile raw;
  state.SetLabel(raw.direct ? "o_direct" : "fadvise-dontneed");
  read_loop(state, [&](uint64_t page, uint64_t count, void* dst) { raw.read(page, count, dst); });
}

void io_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"pages", "random"})->Args({1, 1})->Args({1, 0})->Args({64, 0})->MinTime(0.3)->UseRealTime();
}
BENCHMARK(BM_PageFileRead)->Apply(io_args);
BENCHMARK(BM_RawPread)->Apply(io_args);

// ---- Policy hit ratios on a synthetic walkthrough ----
//
// A quadtree over a 64 x 64 block world, levels 0 (root) to 6 (one block). Every frame the
// viewer's search visits, top down, every node whose box lies within kRadius blocks of the
// viewer's block: the access pattern of an R-tree range query (digest §3.3). Each node is one
// 4 KiB index page. DoV and relevance fall off with block distance. The viewer walks forward
// with random turns and now and then turns back, so old areas are revisited (the case DPLRU is
// meant for, digest §3.4).

constexpr int kLevels = 7;
constexpr int kGrid = 1 << (kLevels - 1);
constexpr float kRadius = 3.0f;

struct Access {
  CacheKey key;
  EntryMeta meta;
};
struct Frame {
  QueryContext query;
  std::vector<Access> accesses;
};

BlockBox node_box(int level, int x, int y) {
  const float size = float(kGrid >> level);
  return {{x * size, y * size, 0}, {(x + 1) * size, (y + 1) * size, 1}};
}

// Visits the nodes whose box meets `view`; DoV falls off with the distance to the viewer's cell.
void visit(int level, int x, int y, const BlockBox& view, const BlockBox& cell, uint64_t frame,
           std::vector<Access>& out) {
  const BlockBox box = node_box(level, x, y);
  if (block_distance(view, box) > 0.0f) return;
  const CacheKey key = (CacheKey(level) << 32) | (CacheKey(x) << 16) | CacheKey(y);
  const float dov = 1.0f / (1.0f + block_distance(cell, box));
  out.push_back({key, EntryMeta{.level = uint32_t(level), .box = box, .dov = dov,
                                .relevance = dov, .frame = frame}});
  if (level + 1 == kLevels) return;
  for (int c = 0; c < 4; ++c) visit(level + 1, 2 * x + c % 2, 2 * y + c / 2, view, cell, frame, out);
}

const std::vector<Frame>& walk_trace() {
  static const std::vector<Frame> trace = [] {
    std::vector<Frame> frames;
    std::mt19937 rng(2002);
    float x = kGrid / 2.0f, y = kGrid / 2.0f, heading = 0.0f;
    for (uint64_t f = 1; f <= 3000; ++f) {
      heading += std::uniform_real_distribution<float>(-0.3f, 0.3f)(rng);
      if (rng() % 200 == 0) heading += 3.14159f;  // turn back
      x += 0.4f * std::cos(heading);
      y += 0.4f * std::sin(heading);
      if (x < 1 || x > kGrid - 1) heading = 3.14159f - heading, x = std::clamp(x, 1.0f, kGrid - 1.0f);
      if (y < 1 || y > kGrid - 1) heading = -heading, y = std::clamp(y, 1.0f, kGrid - 1.0f);
      const BlockBox cell{{std::floor(x), std::floor(y), 0}, {std::floor(x) + 1, std::floor(y) + 1, 1}};
      BlockBox view = cell;
      for (int a = 0; a < 2; ++a) view.lo[a] -= kRadius, view.hi[a] += kRadius;
      Frame frame{{cell, f}, {}};
      visit(0, 0, 0, view, cell, f, frame.accesses);
      frames.push_back(std::move(frame));
    }
    return frames;
  }();
  return trace;
}

using PolicyFactory = std::unique_ptr<ReplacementPolicy> (*)();
std::unique_ptr<ReplacementPolicy> dplru() { return make_distance_priority_lru_policy(); }
std::unique_ptr<ReplacementPolicy> dov_time() { return make_dov_time_policy(); }

// state.range(0) = budget in pages. The root is pinned, as the thesis does.
void policy_hit_ratio(benchmark::State& state, PolicyFactory factory) {
  const std::vector<Frame>& trace = walk_trace();
  BufferCounters counters;
  for (auto _ : state) {
    MemoryBudget budget(uint64_t(state.range(0)) * kPage);
    BufferManager cache(budget, factory());
    const ItemLoader loader = [] {
      return LoadedItem{std::make_shared<const std::array<std::byte, kPage>>(), kPage};
    };
    const Access& root = trace.front().accesses.front();
    cache.get(root.key, root.meta, loader);
    cache.pin(root.key);
    cache.reset_counters();
    for (const Frame& frame : trace) {
      cache.begin_query(frame.query);
      for (const Access& access : frame.accesses) cache.get(access.key, access.meta, loader);
    }
    counters = cache.counters();
  }
  state.counters["hit_ratio"] = double(counters.hits) / double(counters.hits + counters.misses);
  state.counters["misses"] = double(counters.misses);
  state.counters["accesses"] = double(counters.hits + counters.misses);
}

void budget_args(benchmark::internal::Benchmark* b) {
  b->ArgName("pages")->Iterations(1)->Unit(benchmark::kMillisecond);
  for (int pages : {32, 48, 64, 96, 128, 256, 512}) b->Arg(pages);
}
BENCHMARK_CAPTURE(policy_hit_ratio, lru, make_lru_policy)->Apply(budget_args);
BENCHMARK_CAPTURE(policy_hit_ratio, dplru, dplru)->Apply(budget_args);
BENCHMARK_CAPTURE(policy_hit_ratio, dov, make_dov_policy)->Apply(budget_args);
BENCHMARK_CAPTURE(policy_hit_ratio, dov_time, dov_time)->Apply(budget_args);
BENCHMARK_CAPTURE(policy_hit_ratio, hybrid, make_hybrid_relevance_policy)->Apply(budget_args);

}  // namespace
}  // namespace cellwalk

BENCHMARK_MAIN();
