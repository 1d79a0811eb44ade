// Two cube-map modes of the DoV engine (HDoV thesis §5.5.2, digest 000 §3.9) on the same cells,
// interleaved in one run so both see the same machine load: their speeds and how far their
// region DoVs differ (`cellwalk pvs --engine dov --dov-compare N`).
#pragma once

#include <functional>
#include <span>

#include "cellwalk/precompute/engine.hpp"

namespace cellwalk::visibility {

struct DovComparison {
  DovCubes mode = DovCubes::kRays;
  int resolution = 0;
  uint64_t cells = 0;
  // Seconds summed over the cells, one cell at a time (each mode uses every core within a
  // cell): each mode's cube maps and DoVs; and the sampling step 1 both modes share, timed over
  // all cells at once in parallel, as a pvs run computes it.
  double exact_seconds = 0, mode_seconds = 0, step1_seconds = 0;
  // Over every (cell, object) pair either mode sees: the largest |region DoV difference|, and
  // the pairs only one mode sees with the largest DoV among them.
  double max_difference = 0;
  uint64_t pairs = 0, one_sided = 0;
  double one_sided_max_dov = 0;
  double largest_pixel_weight = 0;  // eq. 5.11 at a face's centre pixel: the scale of a difference

  double exact_cells_per_second() const { return double(cells) / exact_seconds; }
  double mode_cells_per_second() const { return double(cells) / mode_seconds; }
  // With step 1, as `pvs --engine dov` runs them.
  double exact_engine_cells_per_second() const { return double(cells) / (exact_seconds + step1_seconds); }
  double mode_engine_cells_per_second() const { return double(cells) / (mode_seconds + step1_seconds); }
};

// Runs exact and options.dov_cubes (at options.dov_resolution) on `cells` of `partition`, one
// cell at a time, alternating which goes first; exact is warmed up on the first cell before any
// timing (GL uploads every mesh once). The fast mode's corner cache serves corners shared with
// an earlier cell: give cells that share none (cells_to_check spreads them) to time cells
// computed on their own. Called with (cells done, cells total).
DovComparison compare_dov_cubes(const World& world, const EngineOptions& options, const ViewCellPartition& partition,
                                std::span<const CellId> cells,
                                const std::function<void(uint64_t, uint64_t)>& progress = {});

}  // namespace cellwalk::visibility
