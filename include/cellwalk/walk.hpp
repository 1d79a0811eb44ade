// The walk harness: replays a camera path with one strategy, headless, and measures every
// frame the same way for every strategy; and the fidelity comparison against ground truth.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "cellwalk/frame_stats.hpp"
#include "cellwalk/path.hpp"
#include "cellwalk/renderer.hpp"
#include "cellwalk/strategy.hpp"

namespace cellwalk {

// Called after each frame with (frames done, frames total).
using ProgressFn = std::function<void(size_t, size_t)>;

// Renders one frame of `strategy` from `camera` and returns its statistics. `time` (the path
// time, seconds) is in stats.time when select() runs, so a strategy can measure velocity.
FrameStats render_frame(Strategy& strategy, Renderer& renderer, const Camera& camera, double time = 0.0);

// Replays every frame of `path`. The camera's lens (fov, aspect, near, far) comes from `lens`.
std::vector<FrameStats> walk(const CameraPath& path, const Camera& lens, Strategy& strategy,
                             Renderer& renderer, const ProgressFn& progress = {});

// Fidelity of one rendered frame against ground truth (the full-detail world, no culling).
struct FidelityFrame {
  int frame = 0;
  double differing_fraction = 0.0;  // pixels whose colour differs at all
  double psnr_db = 0.0;             // over RGB; infinity when identical
  uint64_t visible_objects = 0;     // distinct ids in the ground-truth id buffer
  uint64_t missed_objects = 0;      // of those, absent from the strategy's id buffer
};

struct FidelityImages {
  Image truth, test, difference;
};

// Compares two renderings of the same camera. The difference image is 128 + (test - truth)
// per channel, clamped, as the stratified-rendering thesis shows its errors.
FidelityFrame compare_images(const Image& truth, const IdImage& truth_ids, const Image& test,
                             const IdImage& test_ids, Image* difference);

struct CompareOptions {
  int every = 10;              // compare every k-th frame
  std::string image_dir;       // if set, writes truth/test/diff PNGs of compared frames
  int max_images = 10;         // at most this many frames' images
  std::string label;           // names the images (frameN-LABEL.png); empty: the strategy's name
};

struct FidelitySummary {
  size_t frames = 0;
  double mean_differing_fraction = 0.0, max_differing_fraction = 0.0;
  double mean_psnr_db = 0.0;  // PSNR of the mean squared error over all frames; infinity if none differ
  uint64_t visible_objects = 0, missed_objects = 0;
  double recall = 1.0;        // 1 - missed / visible over all compared frames
};

std::vector<FidelityFrame> compare(const CameraPath& path, const Camera& lens, Strategy& strategy,
                                   Strategy& truth, Renderer& renderer,
                                   const CompareOptions& options, const ProgressFn& progress = {});
FidelitySummary summarize(const std::vector<FidelityFrame>& frames);
void write_fidelity_csv(const std::vector<FidelityFrame>& frames, const std::string& file);
std::string to_json(const FidelitySummary& summary);

}  // namespace cellwalk
