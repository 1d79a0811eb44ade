// Nearest-rank percentiles of a sample, shared by the walk summary and the pixel error.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace cellwalk {

// The sample's value of nearest rank ceil(p / 100 · n): the smallest value with at least p % of
// the sample at or below it; 0 for an empty sample. Reorders `sample` (std::nth_element, O(n)).
// REQUIRES 0 < p <= 100. The 1e-9 keeps a rank that is whole in decimal (99.9 % of 1000 is 999)
// from rounding up in binary.
inline double percentile(std::vector<double>& sample, double p) {
  if (sample.empty()) return 0.0;
  const double rank = std::ceil(p / 100.0 * double(sample.size()) - 1e-9);
  const size_t at = std::clamp<size_t>(size_t(std::max(rank, 1.0)), 1, sample.size()) - 1;
  std::nth_element(sample.begin(), sample.begin() + std::ptrdiff_t(at), sample.end());
  return sample[at];
}

}  // namespace cellwalk
