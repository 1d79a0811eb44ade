// Distances from points and segments to triangles, for the path planner's clearance tests
// (Christer Ericson, Real-Time Collision Detection, 2005: §5.1.5 closest point on a triangle,
// §5.1.9 closest points of two segments; Tomas Möller and Ben Trumbore, Fast, minimum storage
// ray-triangle intersection, 1997).
#pragma once

#include "cellwalk/core/geometry.hpp"

namespace cellwalk::visibility {

// The least distance from point p to the triangle (a, b, c), its inside and its edges
// included. A degenerate triangle (a segment or a point) is measured as what it is.
double point_triangle_distance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);

// The least distance between segment [p, q] (a point when p == q) and the triangle (a, b, c):
// 0 when the segment crosses or touches the triangle.
double segment_triangle_distance(const glm::dvec3& p, const glm::dvec3& q, const glm::dvec3& a, const glm::dvec3& b,
                                 const glm::dvec3& c);

}  // namespace cellwalk::visibility
