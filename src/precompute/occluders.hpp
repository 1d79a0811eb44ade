// Conservative occluders derived from arbitrary meshes, and the single-occluder test from a
// box cell.
// Seeds: 001 vLOD §5.2.2 (occluders must be convex, larger than the cell; concave ones need a
// conservative stand-in) and 000 HDoV thesis §5.5.1 (large convex occluders near the cell; a
// convex occluder hiding an object from the cell's 8 vertices hides it from the cell).
#pragma once

#include <span>
#include <vector>

#include "cellwalk/core/geometry.hpp"
#include "cellwalk/scene/mesh.hpp"

namespace cellwalk::visibility {

struct OccluderParams {
  int grid = 24;           // voxels along the longest side of the mesh's box
  int max_boxes = 3;       // inscribed boxes per mesh
  double min_gain = 0.15;  // a further box must add this fraction of the interior voxels
};

// True when every edge of the mesh (vertices welded by exact position) is used by an even
// number of triangles (a mod-2 cycle): crossing parity along a ray no longer depends on the
// ray, so it defines what is inside. That solid may be empty: a surface written double-sided
// (each triangle twice, in opposite windings) is closed and oriented by this count, but every
// point has even parity and winding number 0. So "closed" never means "encloses volume" by
// itself; only the inside tests below (solid_at, the voxel classification) say what is solid.
bool is_closed(const Mesh& mesh);

struct InscribedBoxes {
  bool closed = false;  // is_closed(mesh); no boxes otherwise
  std::vector<Aabb> boxes;
};

// True when, in addition, every edge is used as often in one direction as in the other: the
// triangles are consistently oriented, and the winding number says what is inside.
bool is_oriented(const Mesh& mesh);

// Whether `point` lies strictly inside the solid a closed mesh bounds (REQUIRES is_closed):
// six rays from it, both ways along three orthonormal directions in no special position, all
// say so (non-zero winding number when `winding`, for an oriented mesh; odd crossing parity
// otherwise) and the two rays along each line agree. Double precision; a ray through an edge
// or vertex, or a point on a triangle, says "not inside", so numerical doubt does not make a
// point solid. A double-sided surface (each
// triangle also in the opposite winding) has winding number 0 and even parity everywhere.
bool solid_at(std::span<const Vec3> positions, std::span<const uint32_t> indices, const Vec3& point,
              bool winding);

// Axis-aligned boxes inside the solid the closed mesh bounds (points of non-zero winding
// number when the mesh is oriented, which counts overlapping closed parts as solid; else of
// odd crossing parity),
// each kept a small margin away from the surface; none when the mesh is not closed or has
// no interior voxel. A voxel counts as interior only when no triangle's plane and box touch
// it and crossing rays along all three axes agree it is inside, so numerical doubt only ever
// drops volume. The boxes may overlap; their union underestimates the solid.
InscribedBoxes inscribed_boxes(const Mesh& mesh, const OccluderParams& params = {});

// Boxes inside a ∪ b that reach across both: for each axis along which a and b overlap or
// touch while their extents on the other two axes overlap with positive size, the box
// spanning both along that axis over the common extent of the other two. Only those that
// are contained in neither a nor b are returned. None when the
// boxes are apart. Occluder shrinking erodes each box alone, so a seam between two abutting
// occluders would open a gap the size of the cell; the bridge closes it (fusion across it).
std::vector<Aabb> bridge_boxes(const Aabb& a, const Aabb& b);

// Whether segment a→b meets the closed box (slab test in double precision).
bool segment_meets_box(const Vec3& a, const Vec3& b, const Aabb& box);

// Segment a→b prepared for many boxes: a cheap filter before segment_meets_box. may_meet
// holds for every box segment_meets_box(a, b, box) holds for (and for some it misses by a
// hair): the box is grown by far more than the rounding of either test.
class SegmentFilter {
 public:
  SegmentFilter(const Vec3& a, const Vec3& b);
  bool may_meet(const Aabb& box) const;

 private:
  glm::dvec3 from_, inverse_;  // inverse_ of the direction, 0 along an axis it does not move
  glm::bvec3 moves_;
  double pad_;                 // grows every box: relative to the coordinates' magnitude
};

// HDoV §5.5.1 made exact for boxes: `occludee` is hidden from every point of `cell` by the
// opaque convex `occluder` when all 64 segments from a cell corner to an occludee corner meet
// the occluder. Why it suffices: for a point q, the viewpoints whose segment to q meets a
// convex occluder form a convex set (the occluder's shadow from q), so containing the cell's
// corners means containing the cell; and for a viewpoint, the points behind the occluder form
// a convex set, so containing the occludee's corners means containing the occludee.
bool occluder_hides(const Aabb& cell, const Aabb& occluder, const Aabb& occludee);

}  // namespace cellwalk::visibility
