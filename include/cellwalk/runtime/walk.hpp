// The walk harness: replays a camera path with one strategy, headless, and measures every
// frame the same way for every strategy. Fidelity against ground truth: metrics/fidelity.hpp.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/strategy/frame_stats.hpp"
#include "cellwalk/render/renderer.hpp"
#include "cellwalk/strategy/strategy.hpp"
#include "cellwalk/strategy/world_textures.hpp"

namespace cellwalk {

// Called after each frame with (frames done, frames total).
using ProgressFn = std::function<void(size_t, size_t)>;

// Renders one frame of `strategy` from `camera` and returns its statistics. `time` (the path
// time, seconds) is in stats.time when select() runs, so a strategy can measure velocity.
// With `drawn`, it receives the items the strategy selected (what compare checks misses against).
// With `render_from`, the strategy selects for `camera` but the frame is drawn from `render_from`
// (the viewer's bird's-eye view: what the walker is shown, seen from above), after `adjust` (if
// set) has changed the selected items (the bird's-eye view's coarser levels).
FrameStats render_frame(Strategy& strategy, Renderer& renderer, const Camera& camera, double time = 0.0,
                        std::vector<DrawItem>* drawn = nullptr, const Camera* render_from = nullptr,
                        const std::function<void(std::vector<DrawItem>&)>& adjust = {});

// Replays every frame of `path`. The camera's lens (fov, aspect, near, far) comes from `lens`.
std::vector<FrameStats> walk(const CameraPath& path, const Camera& lens, Strategy& strategy,
                             Renderer& renderer, const ProgressFn& progress = {});

}  // namespace cellwalk
