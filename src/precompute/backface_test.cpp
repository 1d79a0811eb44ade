// Hierarchical back-face culling from a view cell.
// Seed: 001 vLOD §5.3 (Figs. 8–9), after Kumar et al. 1999; bounding cone after Sederberg &
// Meyers 1988 as corrected by the seed.
#include "precompute/backface_test.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace cellwalk::visibility {
namespace {

constexpr float kPi = 3.14159265358979f;
// Float rounding in the incremental construction: widen every cone by this (radians) so the
// bound stays a bound.
constexpr float kSlack = 1e-5f;

Vec3 corner(const Aabb& b, int i) {
  return {i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z};
}

// In double: acos near 1 would lose most of a float's precision.
float angle_between(const Vec3& a, const Vec3& b) {
  const glm::dvec3 x = glm::normalize(glm::dvec3(a)), y = glm::normalize(glm::dvec3(b));
  return float(std::atan2(glm::length(glm::cross(x, y)), glm::dot(x, y)));
}

Vec3 face_normal(const Mesh& mesh, size_t t) {
  const Vec3& a = mesh.positions[mesh.indices[3 * t]];
  const Vec3& b = mesh.positions[mesh.indices[3 * t + 1]];
  const Vec3& c = mesh.positions[mesh.indices[3 * t + 2]];
  return glm::cross(b - a, c - a);
}

// Exact for one triangle: its plane is behind every corner of the cell, hence (the plane's
// signed distance being linear) behind every point of it. Degenerate triangles are invisible.
bool triangle_back_facing(const Mesh& mesh, size_t t, const Aabb& cell) {
  const glm::dvec3 a = mesh.positions[mesh.indices[3 * t]];
  const glm::dvec3 n = glm::cross(glm::dvec3(mesh.positions[mesh.indices[3 * t + 1]]) - a,
                                  glm::dvec3(mesh.positions[mesh.indices[3 * t + 2]]) - a);
  for (int i = 0; i < 8; ++i)
    if (glm::dot(n, glm::dvec3(corner(cell, i)) - a) >= 0.0) return n == glm::dvec3(0.0);
  return true;
}

struct Cluster {
  const Mesh& mesh;
  const Aabb& cell;
  std::vector<uint32_t> triangles;
  std::vector<bool> back;

  Aabb box_of(size_t begin, size_t end) const {
    Aabb box;
    for (size_t i = begin; i < end; ++i)
      for (int v = 0; v < 3; ++v) box.extend(mesh.positions[mesh.indices[3 * triangles[i] + v]]);
    return box;
  }

  void classify(size_t begin, size_t end) {
    if (end - begin == 1) {
      back[triangles[begin]] = triangle_back_facing(mesh, triangles[begin], cell);
      return;
    }
    const Aabb box = box_of(begin, end);
    std::vector<Vec3> normals;
    normals.reserve(end - begin);
    for (size_t i = begin; i < end; ++i) normals.push_back(face_normal(mesh, triangles[i]));
    const Facing facing = facing_from_cell(box, bound_directions(normals), cell);
    if (facing == Facing::kFront) return;
    if (facing == Facing::kBack) {
      for (size_t i = begin; i < end; ++i) back[triangles[i]] = true;
      return;
    }
    split(begin, end, box);
  }

  // Halves the cluster at the median centroid along the box's longest axis.
  void split(size_t begin, size_t end, const Aabb& box) {
    const Vec3 size = box.size();
    const int axis = size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
    auto centroid = [&](uint32_t t) {
      return mesh.positions[mesh.indices[3 * t]][axis] +
             mesh.positions[mesh.indices[3 * t + 1]][axis] +
             mesh.positions[mesh.indices[3 * t + 2]][axis];
    };
    const size_t mid = begin + (end - begin) / 2;
    std::nth_element(triangles.begin() + begin, triangles.begin() + mid, triangles.begin() + end,
                     [&](uint32_t a, uint32_t b) { return centroid(a) < centroid(b); });
    classify(begin, mid);
    classify(mid, end);
  }
};

}  // namespace

DirectionCone bound_directions(std::span<const Vec3> directions) {
  DirectionCone cone;
  bool first = true;
  for (const Vec3& d : directions) {
    const float length = glm::length(d);
    if (!(length > 0.0f)) continue;
    const Vec3 v = d / length;
    if (first) {
      cone = {v, 0.0f, true};
      first = false;
      continue;
    }
    const float alpha = angle_between(cone.axis, v);
    if (alpha <= cone.half_angle) continue;
    if (alpha + cone.half_angle >= kPi) return {};
    // The old cone's boundary vector opposite v, in the plane of the axis and v; the new cone
    // is the one whose boundary holds both (the seed's V_t = q·A − V, computed by rotation so
    // that θ = 0 needs no special case).
    const Vec3 across = glm::normalize(v - glm::dot(v, cone.axis) * cone.axis);
    const Vec3 opposite =
        std::cos(cone.half_angle) * cone.axis - std::sin(cone.half_angle) * across;
    cone.axis = glm::normalize(opposite + v);
    cone.half_angle = 0.5f * (alpha + cone.half_angle) + kSlack;
  }
  if (first) return {};
  return cone;
}

Facing facing_from_cell(const Aabb& polygons, const DirectionCone& normals, const Aabb& cell) {
  if (!normals.bounded || polygons.overlaps(cell)) return Facing::kMixed;
  float most = 0.0f, least = kPi;
  for (int p = 0; p < 8; ++p) {
    const Vec3 from = corner(polygons, p);
    std::array<Vec3, 8> to_cell;
    for (int c = 0; c < 8; ++c) to_cell[c] = corner(cell, c) - from;
    const DirectionCone view = bound_directions(to_cell);
    if (!view.bounded || view.half_angle >= 0.5f * kPi) return Facing::kMixed;
    const float between = angle_between(normals.axis, view.axis);
    most = std::max(most, between + view.half_angle + normals.half_angle);
    least = std::min(least, between - view.half_angle - normals.half_angle);
  }
  if (most < 0.5f * kPi) return Facing::kFront;
  if (least > 0.5f * kPi) return Facing::kBack;
  return Facing::kMixed;
}

std::vector<bool> back_facing_triangles(const Mesh& mesh, const Aabb& cell) {
  Cluster cluster{mesh, cell, std::vector<uint32_t>(mesh.triangle_count()),
                  std::vector<bool>(mesh.triangle_count(), false)};
  std::iota(cluster.triangles.begin(), cluster.triangles.end(), 0u);
  if (!cluster.triangles.empty()) cluster.classify(0, cluster.triangles.size());
  return cluster.back;
}

}  // namespace cellwalk::visibility
