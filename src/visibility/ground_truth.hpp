// Ground truth for checking visibility engines (issue 4, docs/visibility.md): the union of
// the ids seen in high-resolution ID cube maps from many points of a cell.
#pragma once

#include "visibility/cube_map.hpp"
#include "cellwalk/view_cell.hpp"

namespace cellwalk::visibility {

struct GroundTruthOptions {
  int points = 16;  // random points, half inside the cell and half on its faces, plus the corners
  uint64_t seed = 7;
};

// Ascending ids of the objects that cover a pixel from some point. `cube` fixes the resolution
// (1024² per face by default in `cellwalk pvs --check`). Not exact either: a sliver between
// pixels or seen only from an unsampled point is missed, so it is a lower bound of the truth.
std::vector<ObjectId> ground_truth_visible(const CubeMapRenderer& cube, const ViewCell& cell,
                                           const GroundTruthOptions& options);

}  // namespace cellwalk::visibility
