// Hierarchical back-face culling from a view cell: polygons facing away from every point of
// the cell cannot be seen from it.
// Seed: 001 vLOD §5.3 (Figs. 8–9), after Kumar et al. 1999; bounding cone of unit vectors
// after Sederberg & Meyers 1988 with the error the seed corrects.
#pragma once

#include <span>
#include <vector>

#include "cellwalk/core/geometry.hpp"
#include "cellwalk/scene/mesh.hpp"

namespace cellwalk::visibility {

// The cone of directions within `half_angle` (radians) of the unit vector `axis`.
// bounded == false: no cone narrower than a half-space was found (the test is inconclusive).
struct DirectionCone {
  Vec3 axis{0.0f, 0.0f, 1.0f};
  float half_angle = 0.0f;
  bool bounded = false;
};

// A cone holding every vector of `directions` (need not be unit; zero vectors are skipped),
// built incrementally in O(n): each vector outside the cone so far widens it to the smallest
// cone holding the old one and the vector. Unbounded when the vectors span more than a
// half-space on the way (the seed's α + θ ≥ π case) or when none is non-zero.
DirectionCone bound_directions(std::span<const Vec3> directions);

enum class Facing { kFront, kBack, kMixed };

// vLOD §5.3's test: how polygons within `polygons` (their box) whose normals lie in `normals`
// face the points of `cell`. kBack: every such polygon faces away from every point of the
// cell; kFront: towards every point; otherwise kMixed. REQUIRES for a decisive answer: the
// boxes are disjoint (kMixed otherwise).
Facing facing_from_cell(const Aabb& polygons, const DirectionCone& normals, const Aabb& cell);

// The triangles of `mesh` (face normal from the winding, counter-clockwise front) that face
// away from every point of `cell`: clusters of triangles are tested with facing_from_cell and
// split in two along their longest axis while mixed, down to single triangles, which are
// tested exactly (the plane against the cell's 8 corners). One flag per triangle.
std::vector<bool> back_facing_triangles(const Mesh& mesh, const Aabb& cell);

}  // namespace cellwalk::visibility
