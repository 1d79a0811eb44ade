// Visible sets: from a view cell, which objects can be seen (and how much of the sphere of
// directions each covers, the degree of visibility of HDoV thesis §5.2.1). What run time reads;
// the engines that compute them are in the precompute layer (cellwalk/precompute/engine.hpp).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/visibility/view_cell.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

// Objects visible from a cell, ascending ids. dov is empty, or one value per object (DoV of
// eq. 5.2: the maximum over the cell's sample points of the visible solid angle / 4π).
struct VisibleSet {
  std::vector<ObjectId> objects;
  std::vector<float> dov;
};

// ---- Degree of visibility of groups (HDoV thesis §5.5.3, digest 000 §3.9) ------------------

// Point DoVs at each sample point of a cell: dov[point][i] belongs to objects[i].
struct CornerDov {
  std::vector<ObjectId> objects;
  std::vector<std::vector<float>> dov;
};

// The DoV of an internal node whose subtree holds `members` (ascending ids): the maximum over
// the points of the sum of the members' point DoVs. Exact: the ID buffer counts every pixel of
// the sphere once, so the sum never exceeds 1.
float group_dov(const CornerDov& corners, std::span<const ObjectId> members);
// The cheap bound of thesis §6.2.2: the sum of the members' region DoVs (maxima), clamped to 1.
// Never below group_dov().
float group_dov_upper_bound(const VisibleSet& set, std::span<const ObjectId> members);

}  // namespace cellwalk
