// Cost of the pixel error (src/metrics/pixel_error.cpp) on a 640×480 id frame of ~300 objects,
// the figure compare_images adds per compared frame: both directions against a perturbed copy
// (objects moved by a few pixels, some dropped, some grown), and against itself (the floor).
// Beside it the baseline the windowed search avoids: one full-frame distance transform per id.
//   pixel_error_microbench --benchmark_filter=PixelError
#include <benchmark/benchmark.h>

#include <set>

#include "cellwalk/core/random.hpp"
#include "cellwalk/metrics/pixel_error.hpp"
#include "metrics/distance_transform.hpp"

namespace cellwalk {
namespace {

constexpr int kWidth = 640, kHeight = 480, kObjects = 300;

void paint(IdImage& image, int x0, int y0, int x1, int y1, uint32_t id) {
  for (int y = std::max(y0, 0); y <= std::min(y1, kHeight - 1); ++y)
    for (int x = std::max(x0, 0); x <= std::min(x1, kWidth - 1); ++x)
      image.ids[size_t(y) * kWidth + size_t(x)] = id;
}

// Ground truth: kObjects rectangles of 4 to 80 px a side painted back to front on background.
// The test: the same, each object moved by up to 2 px with probability 0.3, grown by 1 px with
// 0.2, dropped with 0.02.
struct Frames {
  IdImage truth{kWidth, kHeight, std::vector<uint32_t>(size_t(kWidth) * kHeight, kBackgroundId)};
  IdImage test = truth;
  Frames() {
    Random random(14);
    for (uint32_t id = 1; id <= kObjects; ++id) {
      const int x = int(random.integer(0, kWidth - 1)), y = int(random.integer(0, kHeight - 1));
      const int x1 = x + int(random.integer(3, 79)), y1 = y + int(random.integer(3, 79));
      paint(truth, x, y, x1, y1, id);
      if (random.chance(0.02)) continue;
      const int dx = random.chance(0.3) ? int(random.integer(-2, 2)) : 0;
      const int dy = random.chance(0.3) ? int(random.integer(-2, 2)) : 0;
      const int grow = random.chance(0.2) ? 1 : 0;
      paint(test, x + dx - grow, y + dy - grow, x1 + dx + grow, y1 + dy + grow, id);
    }
  }
};

const Frames& frames() {
  static const Frames f;
  return f;
}

void count_differing(benchmark::State& state) {
  const Frames& f = frames();
  size_t differing = 0;
  for (size_t p = 0; p < f.truth.ids.size(); ++p) differing += f.truth.ids[p] != f.test.ids[p];
  state.counters["differing_px"] = double(differing);
  state.counters["visible_ids"] =
      double(std::set<uint32_t>(f.truth.ids.begin(), f.truth.ids.end()).size());
}

void BM_PixelErrorBothWays(benchmark::State& state) {
  const Frames& f = frames();
  PixelErrorStats a, b;
  for (auto _ : state) {
    benchmark::DoNotOptimize(a = pixel_error(f.test, f.truth));
    benchmark::DoNotOptimize(b = pixel_error(f.truth, f.test));
  }
  count_differing(state);
  state.counters["max_px"] = std::max(a.max_px, b.max_px);
  state.counters["p999_px"] = std::max(a.p999_px, b.p999_px);
}
BENCHMARK(BM_PixelErrorBothWays)->Unit(benchmark::kMillisecond);

void BM_PixelErrorIdentical(benchmark::State& state) {
  const Frames& f = frames();
  for (auto _ : state) benchmark::DoNotOptimize(pixel_error(f.truth, f.truth));
}
BENCHMARK(BM_PixelErrorIdentical)->Unit(benchmark::kMillisecond);

// The baseline: a full-frame transform for every id the truth shows, one direction.
void BM_FullFrameTransformPerId(benchmark::State& state) {
  const Frames& f = frames();
  const std::set<uint32_t> ids(f.truth.ids.begin(), f.truth.ids.end());
  std::vector<uint8_t> sites(f.truth.ids.size());
  for (auto _ : state)
    for (uint32_t id : ids) {
      for (size_t p = 0; p < sites.size(); ++p) sites[p] = f.test.ids[p] == id;
      benchmark::DoNotOptimize(squared_distance_transform(sites, kWidth, kHeight));
    }
  state.counters["transforms"] = double(ids.size());
}
BENCHMARK(BM_FullFrameTransformPerId)->Unit(benchmark::kMillisecond);

void BM_OneFullFrameTransform(benchmark::State& state) {
  const Frames& f = frames();
  std::vector<uint8_t> sites(f.truth.ids.size());
  for (size_t p = 0; p < sites.size(); ++p) sites[p] = f.truth.ids[p] == kBackgroundId;
  for (auto _ : state) benchmark::DoNotOptimize(squared_distance_transform(sites, kWidth, kHeight));
}
BENCHMARK(BM_OneFullFrameTransform)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace cellwalk

BENCHMARK_MAIN();
