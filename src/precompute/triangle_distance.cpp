// Distances from points and segments to triangles (Ericson 2005 §5.1.5, §5.1.9; Möller and
// Trumbore 1997), in double precision: the path planner's clearance is a promise.
#include "precompute/triangle_distance.hpp"

#include <algorithm>
#include <cmath>

namespace cellwalk::visibility {

namespace {

using glm::dvec3;

// The closest point of the triangle to p (Ericson §5.1.5: Voronoi regions of the vertices,
// then of the edges, then the face).
dvec3 closest_on_triangle(const dvec3& p, const dvec3& a, const dvec3& b, const dvec3& c) {
  const dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double sum = va + vb + vc;
  if (!(sum > 0)) {  // degenerate: the nearest of its three edges
    dvec3 best = a;
    for (auto [u, v] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
      const double len2 = glm::dot(v - u, v - u);
      const double t = len2 > 0 ? std::clamp(glm::dot(p - u, v - u) / len2, 0.0, 1.0) : 0.0;
      const dvec3 x = u + (v - u) * t;
      if (glm::dot(p - x, p - x) < glm::dot(p - best, p - best)) best = x;
    }
    return best;
  }
  return a + ab * (vb / sum) + ac * (vc / sum);
}

// The least distance between segments [p1, q1] and [p2, q2] (Ericson §5.1.9).
double segment_segment_distance(const dvec3& p1, const dvec3& q1, const dvec3& p2, const dvec3& q2) {
  const dvec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = glm::dot(d1, d1), e = glm::dot(d2, d2), f = glm::dot(d2, r);
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) return glm::length(r);
  if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = glm::dot(d1, r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = glm::dot(d1, d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return glm::length((p1 + d1 * s) - (p2 + d2 * t));
}

// Whether segment [p, q] crosses the triangle (Möller–Trumbore with t in [0, 1]).
bool segment_crosses(const dvec3& p, const dvec3& q, const dvec3& a, const dvec3& b, const dvec3& c) {
  const dvec3 dir = q - p, e1 = b - a, e2 = c - a;
  const dvec3 h = glm::cross(dir, e2);
  const double det = glm::dot(e1, h);
  if (std::abs(det) < 1e-300) return false;  // parallel: the edge distances measure it
  const double inv = 1.0 / det;
  const dvec3 s = p - a;
  const double u = glm::dot(s, h) * inv;
  if (u < 0 || u > 1) return false;
  const dvec3 qv = glm::cross(s, e1);
  const double v = glm::dot(dir, qv) * inv;
  if (v < 0 || u + v > 1) return false;
  const double t = glm::dot(e2, qv) * inv;
  return t >= 0 && t <= 1;
}

}  // namespace

double point_triangle_distance(const dvec3& p, const dvec3& a, const dvec3& b, const dvec3& c) {
  return glm::length(p - closest_on_triangle(p, a, b, c));
}

double segment_triangle_distance(const dvec3& p, const dvec3& q, const dvec3& a, const dvec3& b, const dvec3& c) {
  if (p == q) return point_triangle_distance(p, a, b, c);
  if (segment_crosses(p, q, a, b, c)) return 0.0;
  // Not crossing: the closest pair has an end of the segment or a point of a triangle edge.
  double d = std::min(point_triangle_distance(p, a, b, c), point_triangle_distance(q, a, b, c));
  d = std::min(d, segment_segment_distance(p, q, a, b));
  d = std::min(d, segment_segment_distance(p, q, b, c));
  return std::min(d, segment_segment_distance(p, q, c, a));
}

}  // namespace cellwalk::visibility
