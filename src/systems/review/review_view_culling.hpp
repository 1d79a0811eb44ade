// HDoV thesis §4.3, Fig. 4.15 (digest §3.6): ViewCulling, the exact overlap test of a convex
// cell H (the view frustum cut at REVIEW's depth) and an axis-aligned box R.
#pragma once

#include <array>

#include "cellwalk/core/camera.hpp"
#include "cellwalk/core/geometry.hpp"

namespace cellwalk::review {

// A convex polyhedron with 6 planes and 8 corners, numbered by bits so that corners i and
// i ^ (1, 2 or 4) share an edge: the shape of a frustum.
struct ConvexCell {
  std::array<Vec4, 6> planes;  // a point p is inside when dot(n, p) + d >= 0 for all
  std::array<Vec3, 8> corners;
  Aabb bounds() const;         // the frustum cell of §4.1: the AABB of the corners
};

// The view frustum of `camera` from its near plane to `depth` metres.
ConvexCell frustum_cell(const Camera& camera, float depth);

// Fig. 4.15: false if all of R's vertices are outside one face of H; true if a vertex of R is
// inside H or a vertex of H inside R; else true iff a face of H meets a face of R (tested as
// an edge of either crossing the other solid: for convex solids with no vertex inside the
// other, they meet iff some edge of one crosses the other).
bool view_culling_overlaps(const ConvexCell& h, const Aabb& r);

}  // namespace cellwalk::review
