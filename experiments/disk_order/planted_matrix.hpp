// Planted consecutive-ones matrices: the synthetic input of vLOD §3's Table 1 (seed 001, digest
// §3.5), whose best order is known. Each row is an interval of a hidden column order; with
// `noise`, a row also holds one random column elsewhere; the column ids are shuffled, so the
// identity order is a random one. Used by `cellwalk bench disk-order` and the disk-order tests.
#pragma once

#include <cstdint>
#include <vector>

namespace cellwalk {

struct PlantedMatrix {
  std::vector<std::vector<uint32_t>> rows;  // ascending column ids
  std::vector<uint32_t> hidden;             // hidden[k] = the column at position k of the planted order
};

// `rows` rows over `columns` columns, each an interval of 1 to `max_length` positions (cut at
// the last column). Deterministic for given arguments. REQUIRES columns >= 1, max_length >= 1.
PlantedMatrix planted_matrix(uint32_t columns, uint32_t rows, uint32_t max_length, double noise, uint64_t seed);

}  // namespace cellwalk
