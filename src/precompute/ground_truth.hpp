// Ground truth for checking visibility engines (issue 4, docs/visibility.md): the union of
// the ids seen in high-resolution ID cube maps from many points of a cell.
#pragma once

#include "precompute/cube_map.hpp"
#include <cmath>

#include "cellwalk/visibility/view_cell.hpp"
#include "cellwalk/precompute/engine.hpp"

namespace cellwalk::visibility {

struct GroundTruthOptions {
  int points = 16;  // random points, half inside the cell and half on its faces, plus the corners
  uint64_t seed = 7;
};

// Ascending ids of the objects that cover a pixel from some point. `cube` fixes the resolution
// (1024² per face by default in `cellwalk pvs --check`). Not exact either: a sliver between
// pixels or seen only from an unsampled point is missed, so it is a lower bound of the truth.
std::vector<ObjectId> ground_truth_visible(const CubeMapSource& cube, const ViewCell& cell,
                                           const GroundTruthOptions& options);

}  // namespace cellwalk::visibility

namespace cellwalk::visibility {

// One engine against the ground truth on one cell.
struct CellCheck {
  CellId cell = 0;
  uint64_t set_size = 0;
  uint64_t truth_size = 0;
  uint64_t found = 0;             // ground-truth objects the engine's set contains
  std::vector<ObjectId> missed;   // ground-truth objects it does not
  double engine_seconds = 0.0;
  double truth_seconds = 0.0;
  // Recall: found / truth_size (1 when nothing is visible). Tightness: set_size / truth_size,
  // >= 1 for a conservative engine; how many extra objects it draws.
  double recall() const { return truth_size ? double(found) / double(truth_size) : 1.0; }
  double tightness() const { return truth_size ? double(set_size) / double(truth_size) : (set_size ? INFINITY : 1.0); }
};

// `count` cells with sets (neither solid nor skipped) spread evenly over the ids (all of them when there are fewer).
std::vector<CellId> cells_to_check(const ViewCellPartition& partition, uint64_t count);

CellCheck check_cell(const VisibilityEngine& engine, const CubeMapSource& cube, const ViewCell& cell,
                     const GroundTruthOptions& options);

}  // namespace cellwalk::visibility
