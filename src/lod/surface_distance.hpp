// Point-to-surface distances for measuring how far a LOD level deviates from the original:
// exact point–triangle distance behind a uniform grid searched in growing rings of cells.
// Christer Ericson. Real-Time Collision Detection. 2005, §5.1.5 (closest point on a
// triangle) and §7.1 (uniform grids).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "cellwalk/core/geometry.hpp"

namespace cellwalk {

// Squared distance from p to the triangle abc. Computed from differences to a, so the
// rounding is relative to the triangle's size, not to the coordinates' magnitude.
// A degenerate triangle counts as its edges.
float point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// A fixed set of triangles bucketed in a uniform grid, for nearest-triangle queries.
// Queries are const and may run concurrently.
class TriangleGrid {
 public:
  // Copies the triangles. REQUIRES: every index < positions.size(), indices.size() % 3 == 0,
  // finite positions.
  TriangleGrid(std::span<const Vec3> positions, std::span<const uint32_t> indices);

  // The squared distance from p to the nearest triangle, except that the search stops at
  // the first triangle within sqrt(stop2) and returns that one's squared distance (≤ stop2):
  // all a maximum over points needs. Infinity when there are no triangles.
  // `hint` (any value; 0 to start) names the triangle tried first, and is set to the one
  // found, so that a run of nearby queries mostly stops at the first triangle it tries.
  float nearest2(const Vec3& p, float stop2, uint32_t& hint) const;

 private:
  // A triangle as stored in every cell its box overlaps: a cell's triangles lie side by
  // side, so a query reads them in one sweep.
  struct Entry {
    Vec3 a, b, c;
  };
  using Cell = std::array<int, 3>;

  // Sets the cell size and grid dimensions: kCellEdgeInTriangleEdges, coarsened until cells
  // and entries are linear in the triangle count.
  void choose_cells(const std::vector<Aabb>& boxes, const Vec3& extent, double area);
  void fill_cells(const std::vector<Entry>& triangles, const std::vector<Aabb>& boxes);
  double cells_in(const Aabb& box) const;
  Cell cell_of(const Vec3& p) const;
  size_t cell_index(int x, int y, int z) const;
  static float distance2(const Vec3& p, const Entry& tri) {
    return point_triangle_distance2(p, tri.a, tri.b, tri.c);
  }
  // Lower bound on the distance from p to any triangle outside the block of cells within
  // `ring` of `c`; infinite when that block covers the whole grid.
  float gap_outside_block(const Vec3& p, const Cell& c, int ring) const;

  Vec3 origin_{0.0f};
  float cell_size_ = 1.0f;
  float inverse_cell_size_ = 1.0f;
  float slack_ = 0.0f;  // float rounding of cell coordinates, subtracted from gaps
  Cell dims_{1, 1, 1};
  struct Run {
    uint32_t start, count;
  };
  std::vector<Run> cells_;  // cell i holds entries_[start, start + count)
  std::vector<Entry> entries_;
};

// max(floor2, max over points of the squared distance to the nearest triangle of grid),
// exactly: each query may stop once it is under the running maximum. Points in a spatially
// coherent order (as a vertex-cache-ordered mesh's vertices are) are measured fastest.
float max_nearest2(const TriangleGrid& grid, std::span<const Vec3> points, float floor2);

}  // namespace cellwalk
