// Fidelity against ground truth (the full-detail world, no culling): per frame, differing
// pixels, PSNR, visible objects missed and the pixel error (metrics/pixel_error.hpp, both
// directions); `compare` replays a path with a strategy and the truth side by side
// (src/metrics/fidelity.cpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/metrics/pixel_error.hpp"
#include "cellwalk/render/image.hpp"
#include "cellwalk/render/renderer.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

// Fidelity of one rendered frame against ground truth (the full-detail world, no culling).
struct FidelityFrame {
  int frame = 0;
  double differing_fraction = 0.0;  // pixels whose colour differs at all
  double psnr_db = 0.0;             // over RGB; infinity when identical
  uint64_t visible_objects = 0;     // distinct ids in the ground-truth id buffer
  uint64_t missed_objects = 0;      // of those, absent from the strategy's id buffer
  std::vector<uint32_t> missed_ids; // their pixel ids (renderer.hpp pixel_id), ascending
  uint64_t largest_missed_pixels = 0;  // the most pixels of truth any of them covers; 0 if none
  // Of the missed, those the strategy did draw, as objects at a coarser level than truth's:
  // their pixels fell to a sub-pixel shift of their own level or a neighbour's (an object seen
  // through a slit one pixel wide), not to the visible set. Set by compare(), not compare_images.
  uint64_t missed_drawn = 0;
  int width = 0;                    // of the images, to place PixelErrorStats::worst_pixel
  PixelErrorStats test_to_truth;    // pixel error from the strategy's image to the truth's
  PixelErrorStats truth_to_test;    // and back; unmatched pixels are missed objects' pixels

  // The worse direction: the frame's pixel error and its 99.9th percentile.
  double pixel_error_max_px() const { return std::max(test_to_truth.max_px, truth_to_test.max_px); }
  double pixel_error_p999_px() const {
    return std::max(test_to_truth.p999_px, truth_to_test.p999_px);
  }
};

struct FidelityImages {
  Image truth, test, difference;
};

// Compares two renderings of the same camera; the pixel error compares the id images. The
// difference image is 128 + (test - truth) per channel, clamped, as the stratified-rendering
// thesis shows its errors.
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
  uint64_t missed_drawn = 0;  // of the missed, those drawn (FidelityFrame::missed_drawn)
  uint64_t largest_missed_pixels = 0;  // over the frames
  double recall = 1.0;        // 1 - missed / visible over all compared frames
  // Pixel error (the worse direction of each frame): the largest over frames of the frame's
  // maximum and of its 99.9th percentile, and the fraction of frames where each exceeds 1 px.
  double max_pixel_error_px = 0.0, max_pixel_error_p999_px = 0.0;
  double pixel_error_over_1px_fraction = 0.0, pixel_error_p999_over_1px_fraction = 0.0;
  // Pixels with no match, over all frames: the test shows an id truth lacks / truth shows an id
  // the test lacks. Left out of the figures above.
  uint64_t unmatched_test_pixels = 0, unmatched_truth_pixels = 0;
};

std::vector<FidelityFrame> compare(const CameraPath& path, const Camera& lens, Strategy& strategy,
                                   Strategy& truth, Renderer& renderer,
                                   const CompareOptions& options, const ProgressFn& progress = {});
// Several strategies against one truth rendering per compared frame (the truth costs the most:
// every object at level 0); result[k] is strategies[k]'s. Images are named by each strategy's
// name (by options.label when there is one strategy and a label).
std::vector<std::vector<FidelityFrame>> compare_side_by_side(const CameraPath& path, const Camera& lens,
                                                         std::span<Strategy* const> strategies, Strategy& truth,
                                                         Renderer& renderer, const CompareOptions& options,
                                                         const ProgressFn& progress = {});
// Frames drawn elsewhere (the browser client, web/test/walk.mjs), each against the truth rendered
// here for the same path frame: images of the renderer's size, rows bottom-up.
struct CapturedFrame {
  int frame = 0;  // index into the path
  Image color;
  IdImage ids;
};
// Throws Error naming the frame when one lies outside the path or is not the renderer's size.
std::vector<FidelityFrame> compare_captured(const CameraPath& path, const Camera& lens, std::span<const CapturedFrame> captured,
                                            Strategy& truth, Renderer& renderer, const CompareOptions& options,
                                            const ProgressFn& progress = {});
FidelitySummary summarize(const std::vector<FidelityFrame>& frames);
void write_fidelity_csv(const std::vector<FidelityFrame>& frames, const std::string& file);
std::string to_json(const FidelitySummary& summary);

}  // namespace cellwalk
