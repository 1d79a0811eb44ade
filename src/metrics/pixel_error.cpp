// Pixel error (issue 14): per differing pixel, the distance to the nearest pixel of the other
// image that shows the same id, by an exact distance transform per id over a window that grows
// until it is known to hold every answer. The definition is in cellwalk/metrics/pixel_error.hpp.
#include "cellwalk/metrics/pixel_error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include "cellwalk/core/error.hpp"
#include "metrics/distance_transform.hpp"
#include "metrics/percentile.hpp"

namespace cellwalk {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// The first window's margin around the pixels to answer: most silhouettes that differ at all
// differ by a few pixels, so one small window usually suffices.
constexpr int kFirstMargin = 8;

// Inclusive pixel rectangle.
struct Window {
  int x0, y0, x1, y1;
};

Window bounds_of(const std::vector<uint32_t>& pixels, int width) {
  Window b{std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), -1, -1};
  for (uint32_t p : pixels) {
    const int x = int(p % uint32_t(width)), y = int(p / uint32_t(width));
    b = {std::min(b.x0, x), std::min(b.y0, y), std::max(b.x1, x), std::max(b.y1, y)};
  }
  return b;
}

Window grown(const Window& w, int margin, int width, int height) {
  return {std::max(w.x0 - margin, 0), std::max(w.y0 - margin, 0),
          std::min(w.x1 + margin, width - 1), std::min(w.y1 + margin, height - 1)};
}

// The squared distance from (x, y) inside `w` to the nearest pixel of the image outside `w`, which
// bounds from below the distance to any site the window leaves out; kUnbounded when the window
// is the whole image.
constexpr uint64_t kUnbounded = std::numeric_limits<uint64_t>::max();
uint64_t squared_reach(int x, int y, const Window& w, int width, int height) {
  int64_t reach = std::numeric_limits<int64_t>::max();
  if (w.x0 > 0) reach = std::min<int64_t>(reach, x - w.x0 + 1);
  if (w.x1 < width - 1) reach = std::min<int64_t>(reach, w.x1 - x + 1);
  if (w.y0 > 0) reach = std::min<int64_t>(reach, y - w.y0 + 1);
  if (w.y1 < height - 1) reach = std::min<int64_t>(reach, w.y1 - y + 1);
  return reach == std::numeric_limits<int64_t>::max() ? kUnbounded : uint64_t(reach * reach);
}

// Squared distances, over the window, to the window's pixels of `reference` that show `id`.
std::vector<uint32_t> window_transform(const IdImage& reference, uint32_t id, const Window& w) {
  const int ww = w.x1 - w.x0 + 1, wh = w.y1 - w.y0 + 1;
  std::vector<uint8_t> sites(size_t(ww) * size_t(wh));
  for (int y = 0; y < wh; ++y) {
    const uint32_t* row = reference.ids.data() + size_t(w.y0 + y) * size_t(reference.width) + w.x0;
    for (int x = 0; x < ww; ++x) sites[size_t(y) * size_t(ww) + size_t(x)] = row[x] == id;
  }
  return squared_distance_transform(sites, ww, wh);
}

// distances[p] for the pixels p of `queries`, which all show `id` in `shown`, when `reference`
// shows `id` somewhere. A window answers a pixel when the nearest site inside it is no farther
// than anything outside it; the pixels it leaves unanswered are tried again in a window wide
// enough to hold their nearest site found so far, or, where it held none, twice as wide.
void nearest_of_id(const IdImage& reference, uint32_t id, std::vector<uint32_t> queries,
                   std::vector<double>& distances) {
  const int width = reference.width, height = reference.height;
  int margin = kFirstMargin;
  while (!queries.empty()) {
    const Window w = grown(bounds_of(queries, width), margin, width, height);
    const std::vector<uint32_t> squared = window_transform(reference, id, w);
    std::vector<uint32_t> unanswered;
    int needed = 0;
    bool none_inside = false;
    for (uint32_t p : queries) {
      const int x = int(p % uint32_t(width)), y = int(p / uint32_t(width));
      const uint32_t d2 = squared[size_t(y - w.y0) * size_t(w.x1 - w.x0 + 1) + size_t(x - w.x0)];
      const uint64_t reach2 = squared_reach(x, y, w, width, height);
      if (d2 != kNoSite && d2 <= reach2) {
        distances[p] = std::sqrt(double(d2));
      } else if (reach2 == kUnbounded) {
        distances[p] = kInfinity;  // only when `reference` shows `id` nowhere
      } else {
        unanswered.push_back(p);
        if (d2 == kNoSite) {
          none_inside = true;
        } else {
          needed = std::max(needed, int(std::ceil(std::sqrt(double(d2)))));
        }
      }
    }
    // A window grown by `needed` around an unanswered pixel holds the site found for it, so
    // its nearest; `needed` exceeds `margin` since the site lay beyond the pixel's reach.
    margin = none_inside ? std::max(2 * margin, needed) : needed;
    queries = std::move(unanswered);
  }
}

}  // namespace

std::vector<double> pixel_distances(const IdImage& shown, const IdImage& reference) {
  if (shown.width != reference.width || shown.height != reference.height ||
      shown.ids.size() != reference.ids.size() ||
      shown.ids.size() != size_t(shown.width) * size_t(shown.height))
    fail("pixel error",
         "id images of " + std::to_string(shown.width) + "×" + std::to_string(shown.height) +
             " and " + std::to_string(reference.width) + "×" + std::to_string(reference.height) +
             " pixels (or ids not one per pixel); compare renderings of one size");
  std::vector<double> distances(shown.ids.size(), 0.0);
  std::unordered_map<uint32_t, std::vector<uint32_t>> differing;  // by the id `shown` shows
  for (size_t p = 0; p < shown.ids.size(); ++p)
    if (shown.ids[p] != reference.ids[p]) differing[shown.ids[p]].push_back(uint32_t(p));
  if (differing.empty()) return distances;
  const std::unordered_set<uint32_t> in_reference(reference.ids.begin(), reference.ids.end());
  for (auto& [id, pixels] : differing) {
    if (in_reference.count(id)) {
      nearest_of_id(reference, id, std::move(pixels), distances);
    } else {
      for (uint32_t p : pixels) distances[p] = kInfinity;
    }
  }
  return distances;
}

PixelErrorStats pixel_error_stats(const std::vector<double>& distances) {
  PixelErrorStats s;
  std::vector<double> finite;
  for (size_t p = 0; p < distances.size(); ++p) {
    const double d = distances[p];
    if (d == 0.0) continue;
    if (std::isinf(d)) {
      ++s.unmatched;
    } else {
      finite.push_back(d);
      if (d > s.max_px) {
        s.max_px = d;
        s.worst_pixel = int64_t(p);
      }
    }
  }
  s.p999_px = percentile(finite, 99.9);
  return s;
}

PixelErrorStats pixel_error(const IdImage& shown, const IdImage& reference) {
  return pixel_error_stats(pixel_distances(shown, reference));
}

}  // namespace cellwalk
