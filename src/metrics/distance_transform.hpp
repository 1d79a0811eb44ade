// Exact Euclidean distance transform of a binary image: for every pixel, the squared distance
// between pixel centres to the nearest site. The pixel error of `compare` measures with it
// (src/metrics/pixel_error.cpp).
#pragma once

#include <cstdint>
#include <vector>

namespace cellwalk {

// The squared distance of a pixel with no site anywhere in the image.
constexpr uint32_t kNoSite = UINT32_MAX;

// squared[y * width + x] = min over sites (sx, sy) of (x - sx)² + (y - sy)²: 0 on a site, and
// kNoSite everywhere when no byte of `sites` is nonzero. `sites` is row-major, width × height,
// nonzero where there is a site.
// REQUIRES sites.size() == width * height and 0 <= width, height <= kMaxDistanceTransformSide
// (so that every squared distance fits below kNoSite); fails otherwise.
// Cost: O(width · height), two passes of lower envelopes of parabolas.
constexpr int kMaxDistanceTransformSide = 32767;
std::vector<uint32_t> squared_distance_transform(const std::vector<uint8_t>& sites, int width,
                                                 int height);

}  // namespace cellwalk
