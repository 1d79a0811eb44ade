// HDoV thesis §4.3, Fig. 4.13–4.15 (digest §3.6): ViewCulling, exact convex cell vs box.
#include "systems/review/review_view_culling.hpp"

#include <algorithm>

namespace cellwalk::review {
namespace {

constexpr float kEpsilon = 1e-6f;

float side(const Vec4& plane, const Vec3& p) { return plane.x * p.x + plane.y * p.y + plane.z * p.z + plane.w; }

std::array<Vec3, 8> box_corners(const Aabb& r) {
  std::array<Vec3, 8> c;
  for (int i = 0; i < 8; ++i)
    c[size_t(i)] = Vec3(i & 1 ? r.max.x : r.min.x, i & 2 ? r.max.y : r.min.y, i & 4 ? r.max.z : r.min.z);
  return c;
}

bool inside(const ConvexCell& h, const Vec3& p) {
  return std::all_of(h.planes.begin(), h.planes.end(), [&](const Vec4& pl) { return side(pl, p) >= -kEpsilon; });
}

// Whether segment ab meets box r (slab clipping).
bool segment_meets_box(const Vec3& a, const Vec3& b, const Aabb& r) {
  float t0 = 0.0f, t1 = 1.0f;
  const Vec3 d = b - a;
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(d[axis]) < kEpsilon) {
      if (a[axis] < r.min[axis] || a[axis] > r.max[axis]) return false;
      continue;
    }
    float u = (r.min[axis] - a[axis]) / d[axis], v = (r.max[axis] - a[axis]) / d[axis];
    if (u > v) std::swap(u, v);
    t0 = std::max(t0, u);
    t1 = std::min(t1, v);
    if (t0 > t1) return false;
  }
  return true;
}

// Whether segment ab meets the convex cell h (clipping against its planes).
bool segment_meets_cell(const Vec3& a, const Vec3& b, const ConvexCell& h) {
  float t0 = 0.0f, t1 = 1.0f;
  for (const Vec4& pl : h.planes) {
    const float sa = side(pl, a), sb = side(pl, b);
    if (sa < 0 && sb < 0) return false;
    if (sa < 0) t0 = std::max(t0, sa / (sa - sb));
    else if (sb < 0) t1 = std::min(t1, sa / (sa - sb));
    if (t0 > t1) return false;
  }
  return true;
}

template <typename Fn>
bool any_edge(const std::array<Vec3, 8>& c, Fn fn) {
  for (int i = 0; i < 8; ++i)
    for (int bit : {1, 2, 4})
      if (!(i & bit) && fn(c[size_t(i)], c[size_t(i | bit)])) return true;
  return false;
}

}  // namespace

Aabb ConvexCell::bounds() const {
  Aabb box;
  for (const Vec3& c : corners) box.extend(c);
  return box;
}

ConvexCell frustum_cell(const Camera& camera, float depth) {
  Camera cut = camera;
  cut.far_plane = std::min(camera.far_plane, std::max(depth, camera.near_plane * 2.0f));
  ConvexCell h;
  h.planes = Frustum(cut).planes();
  const Mat4 inverse = glm::inverse(cut.view_projection());
  for (int i = 0; i < 8; ++i) {
    const Vec4 p = inverse * Vec4(i & 1 ? 1.0f : -1.0f, i & 2 ? 1.0f : -1.0f, i & 4 ? 1.0f : -1.0f, 1.0f);
    h.corners[size_t(i)] = Vec3(p) / p.w;
  }
  return h;
}

bool view_culling_overlaps(const ConvexCell& h, const Aabb& r) {
  const std::array<Vec3, 8> rc = box_corners(r);
  for (const Vec4& pl : h.planes)  // lines 1–3: R wholly outside one face of H
    if (std::all_of(rc.begin(), rc.end(), [&](const Vec3& p) { return side(pl, p) < 0; })) return false;
  if (std::any_of(rc.begin(), rc.end(), [&](const Vec3& p) { return inside(h, p); })) return true;    // 4–5
  if (std::any_of(h.corners.begin(), h.corners.end(), [&](const Vec3& p) { return r.contains(p); }))  // 6–7
    return true;
  // Lines 8–11: a face of H meets a face of R.
  return any_edge(h.corners, [&](const Vec3& a, const Vec3& b) { return segment_meets_box(a, b, r); }) ||
         any_edge(rc, [&](const Vec3& a, const Vec3& b) { return segment_meets_cell(a, b, h); });
}

}  // namespace cellwalk::review
