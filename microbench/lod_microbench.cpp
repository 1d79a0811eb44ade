// Benchmarks of the LOD chain builder and the mesh codec on the bunny, each beside its
// baseline: build_lod_chain (simplification, ordering and error measurement of every level)
// vs one raw meshopt_simplify to half; decode vs memcpy of the decoded bytes. Throughput in
// input triangles/s or decoded bytes/s.
#include <benchmark/benchmark.h>
#include <meshoptimizer.h>

#include <cstring>

#include "cellwalk/scene/import.hpp"
#include "cellwalk/lod/lod.hpp"
#include "cellwalk/store/mesh_codec.hpp"

namespace cellwalk {
namespace {

const Mesh& bunny() {
  static const Mesh mesh =
      import_model(std::string(CELLWALK_SOURCE_DIR) + "/data/cgal/meshes/bunny00.off").objects.at(0).mesh;
  return mesh;
}

// The stored form: level 0 of the chain (cache- and fetch-ordered).
const Mesh& stored_bunny() {
  static const Mesh mesh = build_lod_chain(bunny()).levels[0].mesh;
  return mesh;
}

void BM_BuildLodChain(benchmark::State& state) {
  size_t levels = 0;
  for (auto _ : state) levels = build_lod_chain(bunny()).levels.size();
  state.SetItemsProcessed(state.iterations() * int64_t(bunny().triangle_count()));
  state.counters["levels"] = double(levels);
}
BENCHMARK(BM_BuildLodChain)->Unit(benchmark::kMillisecond);

void BM_MeshoptSimplifyHalf(benchmark::State& state) {
  const Mesh& m = bunny();
  std::vector<uint32_t> out(m.indices.size());
  for (auto _ : state) {
    benchmark::DoNotOptimize(meshopt_simplify(out.data(), m.indices.data(), m.indices.size(),
                                              &m.positions[0].x, m.vertex_count(), sizeof(Vec3),
                                              m.indices.size() / 2, 1e30f, 0, nullptr));
  }
  state.SetItemsProcessed(state.iterations() * int64_t(m.triangle_count()));
}
BENCHMARK(BM_MeshoptSimplifyHalf)->Unit(benchmark::kMillisecond);

void BM_Encode(benchmark::State& state) {
  const CodecParams params{16, 8, state.range(0) != 0};
  size_t bytes = 0;
  for (auto _ : state) bytes = encode_mesh(stored_bunny(), params).size();
  state.SetBytesProcessed(state.iterations() * int64_t(stored_bunny().byte_size()));
  state.counters["B/tri"] = double(bytes) / double(stored_bunny().triangle_count());
}
BENCHMARK(BM_Encode)->Arg(0)->Arg(1)->ArgName("zstd")->Unit(benchmark::kMillisecond);

void BM_Decode(benchmark::State& state) {
  const std::vector<uint8_t> bytes = encode_mesh(stored_bunny(), {16, 8, state.range(0) != 0});
  for (auto _ : state) benchmark::DoNotOptimize(decode_mesh(bytes, "bench"));
  state.SetBytesProcessed(state.iterations() * int64_t(stored_bunny().byte_size()));
}
BENCHMARK(BM_Decode)->Arg(0)->Arg(1)->ArgName("zstd")->Unit(benchmark::kMicrosecond);

// The floor for decode: copying the decoded arrays' bytes once.
void BM_MemcpyDecodedSize(benchmark::State& state) {
  const size_t n = stored_bunny().byte_size();
  std::vector<uint8_t> src(n, 1), dst(n);
  for (auto _ : state) {
    std::memcpy(dst.data(), src.data(), n);
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(state.iterations() * int64_t(n));
}
BENCHMARK(BM_MemcpyDecodedSize)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace cellwalk

BENCHMARK_MAIN();
