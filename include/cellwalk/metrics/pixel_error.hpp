// Pixel error: how far, in pixels, the objects of one rendering lie from where another rendering
// of the same camera draws them: the screen-space error measured, where the LOD seeds bound it.
// Not from a seed (issue 14); `compare` reports it both ways against ground truth
// (metrics/fidelity.hpp). Computed with an exact Euclidean distance transform
// (src/metrics/pixel_error.cpp, src/metrics/distance_transform.cpp).
//
// Definition. For two id images of one camera, `shown` and `reference`, and a pixel p where
// they differ (shown(p) != reference(p)), the distance of p from `shown` to `reference` is
//
//   d(p) = min { |p - q| : reference(q) == shown(p) },
//
// the Euclidean distance between pixel centres from p to the nearest pixel where the reference
// shows the object that `shown` shows at p. Background (kBackgroundId) counts as an object like
// any other: where `shown` shows background over an object of `reference`, d(p) is the distance
// to the reference's nearest background. On pixels that agree d(p) = 0; on every differing
// pixel d(p) >= 1 (p itself shows something else in the reference). d(p) is infinite when the
// reference shows that id nowhere: such a pixel is unmatched; it is counted apart and left out
// of the maximum and the percentile, so that they stay finite (its object is one that compare
// already counts as missed or extra).
//
// The two directions of a test image against ground truth:
//   test -> truth (shown = test, reference = truth): where the test draws object a, how far
//     truth's nearest a is. Unmatched: objects truth does not show (and test background when
//     truth shows none).
//   truth -> test (shown = truth, reference = test): where truth draws object b, how far the
//     test's nearest b is. Unmatched: objects the test misses.
// Their maxima are the two directed Hausdorff distances of each object's silhouette, taken over
// the pixels that differ. An object moved by a vector s (over background) gives at most |s| in
// both directions, and exactly |s| for a rectangle; a silhouette grown by one pixel to its four
// neighbours gives at most 1.
#pragma once

#include <cstdint>
#include <vector>

#include "cellwalk/render/image.hpp"

namespace cellwalk {

// d(p) for every pixel, in the images' own layout (index y * width + x): 0 where the two agree,
// the distance above where they differ, infinity where unmatched.
// REQUIRES both images of one size (fails otherwise). Cost: one distance transform per id that
// differing pixels of `shown` show, over a window around those pixels that grows only until it
// holds each one's nearest match, so it is small for objects that differ little.
std::vector<double> pixel_distances(const IdImage& shown, const IdImage& reference);

// One direction's distances summarised over the pixels that differ.
struct PixelErrorStats {
  double max_px = 0.0;     // largest finite d(p); 0 when no pixel differs
  double p999_px = 0.0;    // 99.9th percentile (nearest rank) of the finite d(p); 0 when none
  uint64_t unmatched = 0;  // pixels with d(p) infinite, left out of both figures above
  int64_t worst_pixel = -1;  // index y * width + x of the first pixel at max_px; -1 when none
};

PixelErrorStats pixel_error_stats(const std::vector<double>& distances);

// pixel_error_stats(pixel_distances(shown, reference)).
PixelErrorStats pixel_error(const IdImage& shown, const IdImage& reference);

}  // namespace cellwalk
