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

// Bits 0, 1, 2 … of v moved to bits 0, 3, 6 …: one axis of a Morton key (21 bits).
uint64_t spread_bits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffff;
  v = (v | v << 16) & 0x1f0000ff0000ff;
  v = (v | v << 8) & 0x100f00f00f00f00f;
  v = (v | v << 4) & 0x10c30c30c30c30c3;
  v = (v | v << 2) & 0x1249249249249249;
  return v;
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

// Ericson's Voronoi-region walk. It assumes a proper triangle: with a zero-length edge it
// can settle on that edge's region, so degenerate triangles are taken as their edges.
float point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  if (!(length2(glm::cross(ab, ac)) > 0)) {
    return std::min({segment_distance2(ap, ab), segment_distance2(ap, ac),
                     segment_distance2(p - b, c - b)});
  }
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
  const float area2 = va + vb + vc;  // |ab × ac|², which rounding can still make 0
  if (!(area2 > 0)) {
    return std::min({segment_distance2(ap, ab), segment_distance2(ap, ac),
                     segment_distance2(bp, c - b)});
  }
  return length2(ap - ab * (vb / area2) - ac * (vc / area2));
}

TriangleGrid::TriangleGrid(std::span<const Vec3> positions, std::span<const uint32_t> indices) {
  std::vector<Entry> triangles;
  std::vector<Aabb> boxes;
  triangles.reserve(indices.size() / 3);
  boxes.reserve(indices.size() / 3);
  Aabb box;
  double area = 0.0;
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const Entry tri{positions[indices[t]], positions[indices[t + 1]], positions[indices[t + 2]]};
    boxes.push_back({glm::min(tri.a, glm::min(tri.b, tri.c)), glm::max(tri.a, glm::max(tri.b, tri.c))});
    box.extend(boxes.back());
    area += 0.5 * glm::length(glm::cross(tri.b - tri.a, tri.c - tri.a));
    triangles.push_back(tri);
  }
  if (triangles.empty()) return;
  origin_ = box.min;
  // Rounding of cell coordinates and faces is relative to the coordinates' magnitude.
  slack_ = 8.0f * FLT_EPSILON * (max_component(glm::abs(box.min)) + max_component(glm::abs(box.max)));
  choose_cells(boxes, box.size(), area);
  fill_cells(triangles, boxes);
}

void TriangleGrid::choose_cells(const std::vector<Aabb>& boxes, const Vec3& extent, double area) {
  const double n = double(boxes.size());
  double cell = kCellEdgeInTriangleEdges * std::sqrt(2.0 * area / n);
  if (!(cell > 0.0)) cell = std::max(double(max_component(extent)), 1e-30);
  for (;; cell *= 1.5) {
    std::array<double, 3> dims;
    for (int k = 0; k < 3; ++k) dims[k] = std::max(1.0, std::ceil(extent[k] / cell));
    const double cells = dims[0] * dims[1] * dims[2];
    if (cells > std::max(kMinCells, kMaxCellsPerTriangle * n)) continue;
    cell_size_ = float(cell);
    inverse_cell_size_ = 1.0f / cell_size_;
    for (int k = 0; k < 3; ++k) dims_[k] = int(dims[k]);
    double entries = 0.0;
    for (const Aabb& b : boxes) entries += cells_in(b);
    if (entries <= kMaxEntriesPerTriangle * n + cells) return;
  }
}

double TriangleGrid::cells_in(const Aabb& box) const {
  const Cell lo = cell_of(box.min), hi = cell_of(box.max);
  return double(hi[0] - lo[0] + 1) * double(hi[1] - lo[1] + 1) * double(hi[2] - lo[2] + 1);
}

// Counting sort of (cell, triangle) pairs into cells_ / entries_, with the occupied cells'
// runs laid out in Morton order: a run of nearby queries then reads nearby memory.
void TriangleGrid::fill_cells(const std::vector<Entry>& triangles, const std::vector<Aabb>& boxes) {
  cells_.assign(size_t(dims_[0]) * dims_[1] * dims_[2], {0, 0});
  auto for_each_cell = [&](const Aabb& box, auto fn) {
    const Cell lo = cell_of(box.min), hi = cell_of(box.max);
    for (int z = lo[2]; z <= hi[2]; ++z) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int x = lo[0]; x <= hi[0]; ++x) fn(cell_index(x, y, z));
      }
    }
  };
  for (const Aabb& box : boxes) for_each_cell(box, [&](size_t i) { ++cells_[i].count; });
  std::vector<std::pair<uint64_t, uint32_t>> occupied;  // (Morton key, cell)
  for (uint32_t i = 0; i < cells_.size(); ++i) {
    if (cells_[i].count == 0) continue;
    const uint32_t x = i % dims_[0], y = i / dims_[0] % dims_[1], z = i / dims_[0] / dims_[1];
    occupied.push_back({spread_bits(x) | spread_bits(y) << 1 | spread_bits(z) << 2, i});
  }
  std::sort(occupied.begin(), occupied.end());
  uint32_t next = 0;
  for (const auto& [key, i] : occupied) {
    cells_[i].start = next;
    next += cells_[i].count;
  }
  entries_.resize(next);
  std::vector<uint32_t> cursor(cells_.size());
  for (size_t i = 0; i < cells_.size(); ++i) cursor[i] = cells_[i].start;
  for (size_t t = 0; t < triangles.size(); ++t) {
    for_each_cell(boxes[t], [&](size_t i) { entries_[cursor[i]++] = triangles[t]; });
  }
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

float TriangleGrid::nearest2(const Vec3& p, float stop2, uint32_t& hint) const {
  if (entries_.empty()) return std::numeric_limits<float>::infinity();
  if (hint >= entries_.size()) hint = 0;
  float best2 = distance2(p, entries_[hint]);
  if (best2 <= stop2) return best2;
  // True once a triangle within stop2 is found.
  auto visit = [&](int x, int y, int z) {
    const size_t i = cell_index(x, y, z);
    for (uint32_t e = cells_[i].start, end = e + cells_[i].count; e < end; ++e) {
      const Entry& tri = entries_[e];
      // The box test rejects most of a cell's triangles for the price of a few compares.
      const Vec3 lo = glm::min(tri.a, glm::min(tri.b, tri.c));
      const Vec3 hi = glm::max(tri.a, glm::max(tri.b, tri.c));
      if (length2(glm::max(glm::max(lo - p, p - hi), Vec3(0.0f))) >= best2) continue;
      const float d2 = distance2(p, tri);
      if (d2 < best2) {
        best2 = d2;
        hint = e;
        if (best2 <= stop2) return true;
      }
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
  uint32_t hint = 0;
  for (const Vec3& p : points) worst2 = std::max(worst2, grid.nearest2(p, worst2, hint));
  return worst2;
}

}  // namespace cellwalk
