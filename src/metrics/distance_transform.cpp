// Exact squared Euclidean distance transform, separable: a 1D transform down every column,
// then one along every row of the result.
// Pedro F. Felzenszwalb and Daniel P. Huttenlocher. Distance transforms of sampled functions.
// Theory of Computing 8(19), 2012.
#include "metrics/distance_transform.hpp"

#include <cstddef>
#include <limits>

#include "cellwalk/core/error.hpp"

namespace cellwalk {
namespace {

// Buffers of one 1D transform, reused along every line.
struct LineScratch {
  std::vector<uint32_t> f;  // the line's input
  std::vector<int> v;       // positions of the parabolas in the lower envelope
  std::vector<double> z;    // where each parabola of the envelope starts to be the lowest
};

// line[i * stride] <- min over j of (i - j)² + line[j * stride], for i, j < n; kNoSite entries
// are no parabola at all (skipping them keeps every sum exact in integers). A line with no
// finite entry stays kNoSite.
void transform_line(uint32_t* line, size_t stride, int n, LineScratch& s) {
  s.f.resize(size_t(n));
  s.v.resize(size_t(n));
  s.z.resize(size_t(n) + 1);
  for (int i = 0; i < n; ++i) s.f[size_t(i)] = line[size_t(i) * stride];
  // Where the parabolas from v and q (v < q) cross.
  auto crossing = [&](int v, int q) {
    const int64_t a = int64_t(s.f[size_t(q)]) + int64_t(q) * q;
    const int64_t b = int64_t(s.f[size_t(v)]) + int64_t(v) * v;
    return double(a - b) / double(2 * (q - v));
  };
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (s.f[size_t(q)] == kNoSite) continue;
    if (k < 0) {
      k = 0;
      s.v[0] = q;
      s.z[0] = -std::numeric_limits<double>::infinity();
      s.z[1] = std::numeric_limits<double>::infinity();
      continue;
    }
    double at = crossing(s.v[size_t(k)], q);
    while (at <= s.z[size_t(k)]) at = crossing(s.v[size_t(--k)], q);  // z[0] = -inf stops it
    ++k;
    s.v[size_t(k)] = q;
    s.z[size_t(k)] = at;
    s.z[size_t(k) + 1] = std::numeric_limits<double>::infinity();
  }
  if (k < 0) return;
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (s.z[size_t(k) + 1] < q) ++k;
    const int64_t d = q - s.v[size_t(k)];
    line[size_t(q) * stride] = uint32_t(d * d + s.f[size_t(s.v[size_t(k)])]);
  }
}

}  // namespace

std::vector<uint32_t> squared_distance_transform(const std::vector<uint8_t>& sites, int width,
                                                 int height) {
  if (width < 0 || height < 0 || width > kMaxDistanceTransformSide ||
      height > kMaxDistanceTransformSide)
    fail("distance transform", "image of " + std::to_string(width) + "×" + std::to_string(height) +
                                   " pixels; each side must be 0 to " +
                                   std::to_string(kMaxDistanceTransformSide));
  const size_t w = size_t(width), h = size_t(height);
  if (sites.size() != w * h)
    fail("distance transform", "site mask of " + std::to_string(sites.size()) + " bytes for a " +
                                   std::to_string(width) + "×" + std::to_string(height) +
                                   " image; pass one byte per pixel");
  std::vector<uint32_t> squared(w * h);
  for (size_t i = 0; i < w * h; ++i) squared[i] = sites[i] ? 0 : kNoSite;
  LineScratch scratch;
  for (size_t x = 0; x < w; ++x) transform_line(squared.data() + x, w, height, scratch);
  for (size_t y = 0; y < h; ++y) transform_line(squared.data() + y * w, 1, width, scratch);
  return squared;
}

}  // namespace cellwalk
