// Generator throughput: triangles and objects per second streamed into a counting sink (no
// I/O), for each generator at a typical size. BM_City1e8 builds a 10^8-triangle city and
// reports peak RSS; it takes minutes, so it only runs when asked:
//   generate_bench --benchmark_filter=BM_City1e8
#include <benchmark/benchmark.h>

#include <cstring>
#include <string>

#include "cellwalk/scene/generators.hpp"
#include "cellwalk/core/process_memory.hpp"

namespace {

using namespace cellwalk;

struct CountingSink : ObjectSink {
  SceneCounts counts;
  void add(const Object& o) override { counts.count(o); }
};

template <typename Generate>
void run(benchmark::State& state, Generate generate) {
  SceneCounts total;
  for (auto _ : state) {
    CountingSink sink;
    benchmark::DoNotOptimize(generate(sink));
    total = sink.counts;
  }
  state.counters["objects"] = double(total.objects);
  state.counters["triangles"] = double(total.triangles);
  state.counters["bytes"] = double(total.bytes);
  state.counters["tri/s"] =
      benchmark::Counter(double(total.triangles) * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["obj/s"] =
      benchmark::Counter(double(total.objects) * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["peak_rss"] = double(peak_rss_bytes());
}

void BM_City(benchmark::State& state) {
  CityParams p;
  p.objects = uint64_t(state.range(0));
  p.landmark_fraction = double(state.range(1)) / 1000.0;
  run(state, [&](ObjectSink& s) { return generate_city(p, s); });
}
BENCHMARK(BM_City)
    ->Args({2000, 0})
    ->Args({2000, 10})
    ->Args({20000, 10})
    ->Unit(benchmark::kMillisecond);

void BM_StratifiedCity(benchmark::State& state) {
  StratifiedCityParams p;
  p.blocks_x = p.blocks_z = int(state.range(0));
  run(state, [&](ObjectSink& s) { return generate_stratified_city(p, s); });
}
BENCHMARK(BM_StratifiedCity)->Arg(8)->Arg(32)->Unit(benchmark::kMillisecond);

void BM_Plant(benchmark::State& state) {
  PlantParams p;
  p.units_x = p.units_z = int(state.range(0));
  p.detail = double(state.range(1));
  run(state, [&](ObjectSink& s) { return generate_plant(p, s); });
}
BENCHMARK(BM_Plant)->Args({4, 1})->Args({10, 2})->Unit(benchmark::kMillisecond);

void BM_Grid(benchmark::State& state) {
  GridParams p;
  p.mesh = data_path("cgal/meshes/bunny00.off");
  p.nx = p.nz = int(state.range(0));
  run(state, [&](ObjectSink& s) { return generate_grid(p, s); });
}
BENCHMARK(BM_Grid)->Arg(10)->Unit(benchmark::kMillisecond);

// ~10^8 triangles: 60,000 objects, 1% landmarks (600 bunnies × 75k plus 59,400 buildings).
void BM_City1e8(benchmark::State& state) {
  CityParams p;
  p.objects = 60000;
  p.landmark_fraction = 0.01;
  run(state, [&](ObjectSink& s) { return generate_city(p, s); });
}
BENCHMARK(BM_City1e8)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

// BM_City1e8 is left out unless a filter names it.
int main(int argc, char** argv) {
  bool filtered = false;
  for (int i = 1; i < argc; ++i) filtered |= std::strncmp(argv[i], "--benchmark_filter", 18) == 0;
  std::vector<char*> args(argv, argv + argc);
  std::string skip = "--benchmark_filter=-BM_City1e8";
  if (!filtered) args.push_back(skip.data());
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
