// The process budget of a run (`walk`, `compare`: --budget). A user who says "64 MiB" means the
// process, so everything that grows with the world or the path is charged to that one budget
// (the HDoV thesis's one buffer manager, digest 000 §2.1, taken to the whole process):
//   - the strategy's MemoryBudget: the world's directory, decoded geometry, index pages,
//     visibility data (each strategy charges its own parts);
//   - the renderer's GPU buffer cache: on llvmpipe, host memory mirroring each uploaded mesh,
//     retired buffers included (render/gpu_mesh_cache.hpp);
//   - the path and the per-frame records kept for the report.
// What does not grow with them — code, the GL driver and its compiled shaders, framebuffers,
// thread stacks — is the baseline: measured once the renderer has drawn, reported beside the
// budget, never charged. docs/design.md, "Memory".
#pragma once

#include <cstdint>
#include <optional>

#include "cellwalk/render/renderer.hpp"

namespace cellwalk {

struct RunBudget {
  uint64_t total_bytes = 0;     // 0: no budget; the parts below are then 0 (unbounded)
  uint64_t strategy_bytes = 0;  // the strategy's MemoryBudget
  uint64_t gpu_bytes = 0;       // the renderer's buffer cache (RenderSettings::gpu_budget_bytes)
  uint64_t frames_bytes = 0;    // the path and its per-frame records
};

// The GPU cache's share of a budget when --gpu-budget is not given. On llvmpipe a re-upload is a
// copy, cheaper than the disk read and decode the strategy's cache saves, so the larger part
// goes to the strategy.
inline constexpr double kGpuBudgetShare = 0.25;
// What each frame of a path costs to keep: its PathFrame, its FrameStats and the strategies'
// own per-frame records (REVIEW's ReviewFrame, a share of its query records), rounded up.
inline constexpr uint64_t kBytesPerFrame = 512;

// Splits `total_bytes` (0: none) for a path of `frames` frames. `gpu_bytes` overrides the GPU
// share. Throws Error naming --budget when the GPU share or the frames leave nothing for the
// strategy (each strategy then checks that its part holds what it needs).
RunBudget split_run_budget(uint64_t total_bytes, uint64_t frames, std::optional<uint64_t> gpu_bytes);

// The process's peak resident bytes while a renderer with `settings` (its image size and
// backdrop) draws kWarmUpFrames frames of a synthetic scene: small meshes with and without vertex
// colours through a GPU cache too small to hold them, then kWarmUpBatches full driver batches
// (kDriverBatchTriangles, render/renderer.hpp) of long thin triangles across the screen. By then
// the driver has compiled its shaders and grown its working memory (llvmpipe's binned triangles,
// its freed-buffer pools) to what any one batch needs, and the renderer never queues more. That
// peak is the baseline: it depends on the image, not on the world. REQUIRES: a current GL context.
inline constexpr uint32_t kWarmUpBatches = 3;
inline constexpr int kWarmUpFrames = 3;
uint64_t measure_baseline(const RenderSettings& settings);

}  // namespace cellwalk
