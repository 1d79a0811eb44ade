// Planted consecutive-ones matrices for vLOD §3's Table 1 (seed 001, digest §3.5).
#include "experiments/disk_order/planted_matrix.hpp"

#include <algorithm>
#include <numeric>
#include <utility>

#include "cellwalk/core/random.hpp"

namespace cellwalk {

PlantedMatrix planted_matrix(uint32_t columns, uint32_t rows, uint32_t max_length, double noise, uint64_t seed) {
  Random random(seed);
  PlantedMatrix p{std::vector<std::vector<uint32_t>>(rows), std::vector<uint32_t>(columns)};
  std::iota(p.hidden.begin(), p.hidden.end(), 0u);
  for (uint32_t i = columns; i > 1; --i) std::swap(p.hidden[i - 1], p.hidden[size_t(random.integer(0, i - 1))]);
  for (auto& row : p.rows) {
    const auto first = uint32_t(random.integer(0, columns - 1));
    const uint32_t last = std::min(columns - 1, first + uint32_t(random.integer(1, max_length)) - 1);
    for (uint32_t k = first; k <= last; ++k) row.push_back(p.hidden[k]);
    if (random.chance(noise)) row.push_back(uint32_t(random.integer(0, columns - 1)));
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
  }
  return p;
}

}  // namespace cellwalk
