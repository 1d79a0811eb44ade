// Point-to-surface distances: exact point–triangle distance and a uniform grid of triangles
// searched in growing rings of cells around the query point.
// Christer Ericson. Real-Time Collision Detection. 2005, §5.1.5 (closest point on a
// triangle) and §7.1 (uniform grids).
#include "lod/surface_distance.hpp"

#include <cfloat>
#include <cmath>

namespace cellwalk {
namespace {

// A cell's edge, in units of a typical triangle's edge sqrt(2 · area / triangles): a few
// triangles per occupied cell, and a triangle in a few cells.
constexpr float kCellEdgeInTriangleEdges = 2.0f;
// Grids of sparse or elongated meshes get coarser cells so that memory stays linear.
constexpr double kMaxCellsPerTriangle = 4.0;
constexpr double kMaxEntriesPerTriangle = 16.0;
constexpr double kMinCells = 64.0;

float max_component(const Vec3& v) {
  return std::max({v.x, v.y, v.z});
}

float length2(const Vec3& v) {
  return glm::dot(v, v);
}

// Squared distance from a point to a segment, both relative to the segment's start.
float segment_distance2(const Vec3& ap, const Vec3& ab) {
  const float len2 = length2(ab);
  const float t = len2 > 0.0f ? std::clamp(glm::dot(ap, ab) / len2, 0.0f, 1.0f) : 0.0f;
  return length2(ap - ab * t);
}

}  // namespace

// Ericson's Voronoi-region walk; edges go through segment_distance2, which also covers
// zero-length edges.
float point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return length2(ap);
  const Vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return length2(bp);
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return segment_distance2(ap, ab);
  const Vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return length2(cp);
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return segment_distance2(ap, ac);
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return segment_distance2(bp, c - b);
  const float area2 = va + vb + vc;  // |ab × ac|², 0 for a degenerate triangle
  if (!(area2 > 0)) {
    return std::min({segment_distance2(ap, ab), segment_distance2(ap, ac),
                      segment_distance2(bp, c - b)});
  }
  return length2(ap - ab * (vb / area2) - ac * (vc / area2));
}

TriangleGrid::TriangleGrid(std::span<const Vec3> positions, std::span<const uint32_t> indices) {
  Aabb box;
  double area = 0.0;
  triangles_.reserve(indices.size() / 3);
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const std::array<Vec3, 3> tri{positions[indices[t]], positions[indices[t + 1]],
                                  positions[indices[t + 2]]};
    for (const Vec3& v : tri) box.extend(v);
    area += 0.5 * glm::length(glm::cross(tri[1] - tri[0], tri[2] - tri[0]));
    triangles_.push_back(tri);
  }
  if (triangles_.empty()) return;
  origin_ = box.min;
  const Vec3 extent = box.size();
  const double n = double(triangles_.size());
  // Rounding of cell coordinates and faces is relative to the coordinates' magnitude.
  slack_ = 8.0f * FLT_EPSILON * (max_component(glm::abs(box.min)) + max_component(glm::abs(box.max)));

  double cell = kCellEdgeInTriangleEdges * std::sqrt(2.0 * area / n);
  if (!(cell > 0.0)) cell = std::max(double(max_component(extent)), 1e-30);
  std::array<double, 3> dims{};
  for (;;) {
    for (int k = 0; k < 3; ++k) dims[k] = std::max(1.0, std::ceil(extent[k] / cell));
    const double cells = dims[0] * dims[1] * dims[2];
    if (cells <= std::max(kMinCells, kMaxCellsPerTriangle * n)) {
      set_cells(float(cell), dims);
      if (double(entry_count()) <= kMaxEntriesPerTriangle * n + cells) break;
    }
    cell *= 1.5;
  }
  fill_cells();
}

void TriangleGrid::set_cells(float cell, const std::array<double, 3>& dims) {
  cell_size_ = cell;
  inverse_cell_size_ = 1.0f / cell;
  for (int k = 0; k < 3; ++k) dims_[k] = int(dims[k]);
}

size_t TriangleGrid::entry_count() const {
  size_t entries = 0;
  for (const auto& tri : triangles_) {
    const auto [lo, hi] = cell_range(tri);
    entries += size_t(hi[0] - lo[0] + 1) * size_t(hi[1] - lo[1] + 1) * size_t(hi[2] - lo[2] + 1);
  }
  return entries;
}

// Counting sort of (cell, triangle) pairs into cell_start_ / cell_triangles_.
void TriangleGrid::fill_cells() {
  cell_start_.assign(size_t(dims_[0]) * dims_[1] * dims_[2] + 1, 0);
  auto for_each_cell = [&](const std::array<Vec3, 3>& tri, auto fn) {
    const auto [lo, hi] = cell_range(tri);
    for (int z = lo[2]; z <= hi[2]; ++z) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int x = lo[0]; x <= hi[0]; ++x) fn(cell_index(x, y, z));
      }
    }
  };
  for (const auto& tri : triangles_) for_each_cell(tri, [&](size_t i) { ++cell_start_[i + 1]; });
  for (size_t i = 1; i < cell_start_.size(); ++i) cell_start_[i] += cell_start_[i - 1];
  cell_triangles_.resize(cell_start_.back());
  std::vector<uint32_t> cursor(cell_start_.begin(), cell_start_.end() - 1);
  for (uint32_t t = 0; t < triangles_.size(); ++t) {
    for_each_cell(triangles_[t], [&](size_t i) { cell_triangles_[cursor[i]++] = t; });
  }
}

std::pair<TriangleGrid::Cell, TriangleGrid::Cell> TriangleGrid::cell_range(
    const std::array<Vec3, 3>& tri) const {
  return {cell_of(glm::min(tri[0], glm::min(tri[1], tri[2]))),
          cell_of(glm::max(tri[0], glm::max(tri[1], tri[2])))};
}

TriangleGrid::Cell TriangleGrid::cell_of(const Vec3& p) const {
  Cell c;
  for (int k = 0; k < 3; ++k) {
    // Clamped as float first: a far point must not overflow the int.
    const float f = (p[k] - origin_[k]) * inverse_cell_size_;
    c[k] = int(std::clamp(f, 0.0f, float(dims_[k] - 1)));
  }
  return c;
}

size_t TriangleGrid::cell_index(int x, int y, int z) const {
  return (size_t(z) * dims_[1] + y) * dims_[0] + x;
}

float TriangleGrid::gap_outside_block(const Vec3& p, const Cell& c, int ring) const {
  float gap = std::numeric_limits<float>::infinity();  // no cell left: nothing unseen
  for (int k = 0; k < 3; ++k) {
    if (c[k] - ring > 0) gap = std::min(gap, p[k] - (origin_[k] + (c[k] - ring) * cell_size_));
    if (c[k] + ring < dims_[k] - 1) {
      gap = std::min(gap, origin_[k] + (c[k] + ring + 1) * cell_size_ - p[k]);
    }
  }
  return std::max(0.0f, gap - slack_);
}

float TriangleGrid::nearest2(const Vec3& p, float stop2) const {
  float best2 = std::numeric_limits<float>::infinity();
  if (triangles_.empty()) return best2;
  // True once a triangle within stop2 is found.
  auto visit = [&](int x, int y, int z) {
    const size_t i = cell_index(x, y, z);
    for (uint32_t e = cell_start_[i]; e < cell_start_[i + 1]; ++e) {
      const auto& tri = triangles_[cell_triangles_[e]];
      best2 = std::min(best2, point_triangle_distance2(p, tri[0], tri[1], tri[2]));
      if (best2 <= stop2) return true;
    }
    return false;
  };
  const Cell c = cell_of(p);
  for (int ring = 0;; ++ring) {
    // The shell of cells at Chebyshev distance `ring` from c, clipped to the grid.
    const int x0 = std::max(0, c[0] - ring), x1 = std::min(dims_[0] - 1, c[0] + ring);
    for (int z = std::max(0, c[2] - ring); z <= std::min(dims_[2] - 1, c[2] + ring); ++z) {
      for (int y = std::max(0, c[1] - ring); y <= std::min(dims_[1] - 1, c[1] + ring); ++y) {
        if (std::abs(z - c[2]) == ring || std::abs(y - c[1]) == ring) {
          for (int x = x0; x <= x1; ++x) {
            if (visit(x, y, z)) return best2;
          }
          continue;
        }
        if (c[0] - ring == x0 && visit(x0, y, z)) return best2;
        if (ring > 0 && c[0] + ring == x1 && visit(x1, y, z)) return best2;
      }
    }
    const float gap = gap_outside_block(p, c, ring);
    if (gap * gap >= best2) return best2;
  }
}

float max_nearest2(const TriangleGrid& grid, std::span<const Vec3> points, float floor2) {
  float worst2 = floor2;
  for (const Vec3& p : points) worst2 = std::max(worst2, grid.nearest2(p, worst2));
  return worst2;
}

}  // namespace cellwalk
