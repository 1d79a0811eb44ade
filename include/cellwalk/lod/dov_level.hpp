// HDoV thesis eqs. 5.5 and 5.6 (digest 000 §3.10): a level of detail chosen by degree of
// visibility. The target is k·T_finest + (1 − k)·T_coarsest triangles, with k = min(DoV /
// MAXDOV, 1) for an object (eq. 5.6) or DoV / η for an internal node (eq. 5.5), snapped to the
// stored level nearest it. VISUAL (ch. 5) and the scene tree's VSC and PB (ch. 6) all use these.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace cellwalk {

// k of eq. 5.6. REQUIRES: max_dov > 0.
inline double dov_weight(double dov, double max_dov) { return std::min(dov / max_dov, 1.0); }

// Eqs. 5.5 / 5.6: the triangle target for weight k in [0, 1].
inline double dov_triangle_target(double k, double finest, double coarsest) {
  return k * finest + (1.0 - k) * coarsest;
}

// The level of `count` (>= 1) whose triangles(level) is nearest `target`; ties go to the finer.
template <class Triangles>
uint32_t nearest_level(uint32_t count, double target, Triangles triangles) {
  uint32_t best = 0;
  double best_gap = std::abs(double(triangles(0u)) - target);
  for (uint32_t l = 1; l < count; ++l) {
    const double gap = std::abs(double(triangles(l)) - target);
    if (gap < best_gap) best = l, best_gap = gap;
  }
  return best;
}

}  // namespace cellwalk
