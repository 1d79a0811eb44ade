// Renderer throughput on this machine's OpenGL (llvmpipe without a GPU): triangles per second
// for draw lists of 10^5, 10^6 and 10^7 triangles at 640×480, reported as items_per_second.
// A grid of UV spheres of 10^4 triangles each, seen from above so all of them are in view.
//   Resident: every mesh already in the GPU cache (the steady state of a walkthrough).
//   Streaming: a zero budget, so every mesh is uploaded, drawn and freed each frame.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <vector>

#include "cellwalk/render/renderer.hpp"

namespace cellwalk {
namespace {

constexpr int kStacks = 50;
constexpr int kSlices = 100;  // 2 × 50 × 100 = 10^4 triangles per sphere
constexpr uint64_t kTrianglesPerSphere = 2ull * kStacks * kSlices;
constexpr float kSpacing = 3.0f;

Mesh unit_sphere() {
  Mesh mesh;
  for (int i = 0; i <= kStacks; ++i) {
    float theta = float(M_PI) * i / kStacks;
    for (int j = 0; j <= kSlices; ++j) {
      float phi = 2.0f * float(M_PI) * j / kSlices;
      Vec3 n(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
      mesh.positions.push_back(n);
      mesh.normals.push_back(n);
    }
  }
  for (uint32_t i = 0; i < kStacks; ++i) {
    for (uint32_t j = 0; j < kSlices; ++j) {
      uint32_t a = i * (kSlices + 1) + j, b = a + 1, c = a + kSlices + 1, d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, c, b, b, c, d});
    }
  }
  return mesh;
}

int grid_side(uint64_t spheres) {
  return int(std::ceil(std::sqrt(double(spheres))));
}

// Sphere `object` of the grid: the unit sphere moved to its cell. The returned pointer stays
// valid until the next call, as MeshProvider allows.
class SphereGrid {
 public:
  explicit SphereGrid(uint64_t spheres) : side_(grid_side(spheres)), unit_(unit_sphere()) {
    for (uint64_t i = 0; i < spheres; ++i) {
      items_.push_back({ObjectId(i), 0, rgba8(uint8_t(60 + i * 37 % 190), 150, 200)});
    }
  }
  const std::vector<DrawItem>& items() const { return items_; }
  MeshProvider provider() {
    return [this](const DrawItem& item) {
      scratch_ = unit_;
      Vec3 offset = cell_center(item.id);
      for (Vec3& p : scratch_.positions) p += offset;
      return &scratch_;
    };
  }
  // Above the grid's front edge looking down at its middle.
  Camera camera() const {
    float extent = side_ * kSpacing;
    Camera camera;
    camera.position = Vec3(0.0f, 0.9f * extent, 0.9f * extent);
    camera.pitch_deg = -42.0f;
    camera.far_plane = 4.0f * extent;
    return camera;
  }

 private:
  Vec3 cell_center(ObjectId id) const {
    float half = 0.5f * (side_ - 1) * kSpacing;
    return Vec3(float(id % side_) * kSpacing - half, 0.0f, float(id / side_) * kSpacing - half);
  }

  int side_;
  Mesh unit_;
  Mesh scratch_;
  std::vector<DrawItem> items_;
};

GlContext& context() {
  static std::unique_ptr<GlContext> context = GlContext::headless();
  return *context;
}

void run(benchmark::State& state, uint64_t budget_bytes) {
  context();
  uint64_t triangles = uint64_t(state.range(0));
  SphereGrid grid(triangles / kTrianglesPerSphere);
  RenderSettings settings;  // 640×480
  settings.gpu_budget_bytes = budget_bytes;
  Renderer renderer(settings);
  MeshProvider provider = grid.provider();
  renderer.render(grid.camera(), grid.items(), provider);  // warm-up: fills the cache
  RenderStats stats;
  for (auto _ : state) stats = renderer.render(grid.camera(), grid.items(), provider);
  state.SetItemsProcessed(int64_t(stats.triangles) * state.iterations());
  state.counters["ms_per_frame"] = stats.ms;
  state.counters["uploaded_MB"] = double(stats.uploaded_bytes) / 1e6;
  state.SetLabel(context().renderer_name());
}

void BM_RenderResident(benchmark::State& state) {
  run(state, 1ull << 30);
}
void BM_RenderStreaming(benchmark::State& state) {
  run(state, 0);
}

BENCHMARK(BM_RenderResident)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_RenderResident)
    ->Arg(10'000'000)
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_RenderStreaming)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace cellwalk

BENCHMARK_MAIN();
