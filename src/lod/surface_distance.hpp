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

#include "cellwalk/geometry.hpp"

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
  float nearest2(const Vec3& p, float stop2) const;

 private:
  using Cell = std::array<int, 3>;
  void set_cells(float cell_size, const std::array<double, 3>& dims);
  // (cell, triangle) pairs the current cell size would store.
  size_t entry_count() const;
  void fill_cells();
  // The first and last cell of a triangle's box.
  std::pair<Cell, Cell> cell_range(const std::array<Vec3, 3>& tri) const;
  Cell cell_of(const Vec3& p) const;
  size_t cell_index(int x, int y, int z) const;
  // Lower bound on the distance from p to any triangle outside the block of cells within
  // `ring` of `c`; negative when that block covers the whole grid.
  float gap_outside_block(const Vec3& p, const Cell& c, int ring) const;

  std::vector<std::array<Vec3, 3>> triangles_;
  Vec3 origin_{0.0f};
  float cell_size_ = 1.0f;
  float inverse_cell_size_ = 1.0f;
  float slack_ = 0.0f;  // float rounding of cell coordinates, subtracted from gaps
  Cell dims_{1, 1, 1};
  std::vector<uint32_t> cell_start_;      // CSR: cell i holds cell_triangles_[start[i], start[i+1])
  std::vector<uint32_t> cell_triangles_;  // a triangle is in every cell its box overlaps
};

// max(floor2, max over points of the squared distance to the nearest triangle of grid),
// exactly: each query may stop once it is under the running maximum.
float max_nearest2(const TriangleGrid& grid, std::span<const Vec3> points, float floor2);

}  // namespace cellwalk
