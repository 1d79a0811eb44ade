// The process budget of a run, split between the strategy, the GPU cache and the path
// (cellwalk/runtime/run_budget.hpp).
#include "cellwalk/runtime/run_budget.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/core/process_memory.hpp"

namespace cellwalk {

namespace {


// A fan of `triangles` long thin triangles from the screen centre to a rim far past the
// screen's corners, coloured or not: each triangle crosses as many of llvmpipe's tiles as a
// triangle that small in area can.
Mesh warm_up_mesh(bool colored, uint32_t triangles) {
  Mesh mesh;
  mesh.positions.push_back(Vec3(0.0f, 0.0f, 0.0f));
  for (uint32_t i = 0; i <= triangles; ++i) {
    const float a = 6.2831853f * float(i) / float(triangles);
    mesh.positions.push_back(Vec3(20.0f * std::cos(a), 20.0f * std::sin(a), 0.0f));
  }
  for (uint32_t i = 1; i <= triangles; ++i) mesh.indices.insert(mesh.indices.end(), {0u, i, i + 1});
  if (colored) mesh.colors.assign(mesh.positions.size(), rgba8(90, 160, 220));
  return mesh;
}

}  // namespace

RunBudget split_run_budget(uint64_t total_bytes, uint64_t frames, std::optional<uint64_t> gpu_bytes) {
  if (total_bytes == 0) return {};
  RunBudget b;
  b.total_bytes = total_bytes;
  b.frames_bytes = frames * kBytesPerFrame;
  b.gpu_bytes = gpu_bytes ? *gpu_bytes : uint64_t(double(total_bytes) * kGpuBudgetShare);
  if (b.gpu_bytes + b.frames_bytes >= total_bytes)
    fail("--budget", "a memory budget of " + byte_size_text(total_bytes) + " is too small: the GPU cache (" +
                         byte_size_text(b.gpu_bytes) + ") and the path's " + std::to_string(frames) + " frames (" +
                         byte_size_text(b.frames_bytes) +
                         ") leave nothing for the strategy; give a larger --budget or a smaller --gpu-budget");
  b.strategy_bytes = total_bytes - b.gpu_bytes - b.frames_bytes;
  return b;
}

uint64_t measure_baseline(const RenderSettings& settings) {
  reset_peak_rss();
  // Fans of 64 to 8192 triangles with and without vertex colours, through a GPU cache an eighth
  // of their size so the driver also frees and reuses buffers; then full batches of the largest.
  std::vector<Mesh> meshes;
  std::vector<DrawItem> items;
  uint64_t bytes = 0;
  for (uint32_t i = 0; i < 16; ++i) {
    meshes.push_back(warm_up_mesh(i % 2 == 0, 64u << (i % 8)));
    items.push_back({i, 0, rgba8(200, 200, 200), DrawKind::kPatch});
    bytes += meshes.back().byte_size();
  }
  meshes.push_back(warm_up_mesh(true, kDriverBatchTriangles));
  for (uint32_t i = 0; i < kWarmUpBatches; ++i)
    items.push_back({uint32_t(meshes.size() - 1), i, rgba8(200, 200, 200), DrawKind::kPatch});
  RenderSettings churn = settings;
  churn.gpu_budget_bytes = std::max(bytes / 8, meshes.back().byte_size());
  {
    Renderer renderer(churn);
    Camera camera;
    camera.position = Vec3(0.0f, 0.0f, 3.0f);
    for (int frame = 0; frame < kWarmUpFrames; ++frame)
      renderer.render(camera, items, [&](const DrawItem& item) { return &meshes[item.id]; });
  }
  return peak_rss_bytes();
}

}  // namespace cellwalk
