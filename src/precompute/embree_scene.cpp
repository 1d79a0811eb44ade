// The world's level-0 triangles in an Embree 3 scene: nearest-hit rays, and point-in-solid
// against closed meshes only (vLOD §5; HDoV thesis §5.5; solid view cells, docs/visibility.md).
#include "precompute/embree_scene.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <mutex>

#include "cellwalk/core/error.hpp"
#include "precompute/occluders.hpp"
#include "precompute/triangle_distance.hpp"

namespace cellwalk::visibility {

namespace {

RTCRayHit make_ray(const Vec3& o, const Vec3& d, float near, float far) {
  RTCRayHit rh{};
  rh.ray.org_x = o.x;
  rh.ray.org_y = o.y;
  rh.ray.org_z = o.z;
  rh.ray.dir_x = d.x;
  rh.ray.dir_y = d.y;
  rh.ray.dir_z = d.z;
  rh.ray.tnear = near;
  rh.ray.tfar = far;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

static_assert(sizeof(Vec3) == 3 * sizeof(float), "Embree's FLOAT3 vertices are read as Vec3");

// The geometry, and the mesh's arrays as copied into Embree's buffers (which live as long as
// the scene holds the geometry).
RTCGeometry make_geometry(RTCDevice device, const Mesh& mesh, std::span<const Vec3>& positions,
                          std::span<const uint32_t>& indices) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<Vec3*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                       sizeof(Vec3), mesh.vertex_count()));
  std::memcpy(v, mesh.positions.data(), mesh.vertex_count() * sizeof(Vec3));
  auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                           3 * sizeof(uint32_t), mesh.triangle_count()));
  std::memcpy(t, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
  rtcCommitGeometry(g);
  positions = {v, mesh.vertex_count()};
  indices = {t, mesh.indices.size()};
  return g;
}

}  // namespace

EmbreeScene::EmbreeScene(const World& world)
    : world_(world), solids_(world.object_count()), positions_(world.object_count()), indices_(world.object_count()) {
  device_ = rtcNewDevice(nullptr);
  if (!device_) fail("embree", "cannot create a device (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  scene_ = rtcNewScene(device_);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
  // Watertight ray–triangle tests: a ray through an edge two triangles share hits one of them
  // (without it, rays passed between the faces of levels, docs/surface-occluders.md).
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  std::mutex attach;
  tbb::parallel_for(size_t(0), world.object_count(), [&](size_t i) {
    const auto id = static_cast<ObjectId>(i);
    const Mesh mesh = world.decode_level(id, 0, world.read_level(id, 0));
    if (mesh.triangle_count() == 0) return;
    Solid& solid = solids_[i];
    solid.closed = visibility::is_closed(mesh);
    solid.oriented = solid.closed && visibility::is_oriented(mesh);
    RTCGeometry g = make_geometry(device_, mesh, solid.positions, solid.indices);
    positions_[i] = solid.positions;
    indices_[i] = solid.indices;
    std::lock_guard lock(attach);
    rtcAttachGeometryByID(scene_, g, id);
    rtcReleaseGeometry(g);
  });
  rtcCommitScene(scene_);
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

std::optional<ObjectId> EmbreeScene::first_hit(const Vec3& origin, const Vec3& dir, float far) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh = make_ray(origin, dir, 0.0f, far);
  rtcIntersect1(scene_, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  return rh.hit.geomID;
}

void EmbreeScene::first_hits(const Vec3& origin, std::span<const Vec3> dirs, float near, float far,
                             std::span<uint32_t> ids) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // one origin, neighbouring directions
  constexpr size_t kStream = 256;
  std::array<RTCRayHit, kStream> rays;
  for (size_t from = 0; from < dirs.size(); from += kStream) {
    const size_t n = std::min(kStream, dirs.size() - from);
    // Unit directions with t rescaled: Embree 3.13's coherent traversal misses hits (rays pass
    // through walls) when directions are not unit length.
    for (size_t i = 0; i < n; ++i) {
      const float length = glm::length(dirs[from + i]);
      rays[i] = make_ray(origin, dirs[from + i] / length, near * length, far * length);
    }
    rtcIntersect1M(scene_, &context, rays.data(), unsigned(n), sizeof(RTCRayHit));
    for (size_t i = 0; i < n; ++i)
      ids[from + i] = rays[i].hit.geomID == RTC_INVALID_GEOMETRY_ID ? 0 : rays[i].hit.geomID + 1;
  }
}

std::optional<EmbreeScene::Hit> EmbreeScene::hit(const Vec3& origin, const Vec3& dir, float near, float far) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh = make_ray(origin, dir, near, far);
  rtcIntersect1(scene_, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  const Vec3 n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  const float length = glm::length(n);
  return Hit{rh.ray.tfar, rh.hit.geomID, length > 0 ? n / length : Vec3(0.0f)};
}

namespace {

// What a point query over the scene's triangles carries to its callback.
struct SegmentQuery {
  const std::vector<std::span<const Vec3>>* positions;
  const std::vector<std::span<const uint32_t>>* indices;
  glm::dvec3 a, b;
  double clearance = 0;  // clear(): a triangle nearer than this ends the query
  double above_y = 0;    // distance_above(): triangles wholly at or below it are skipped
  bool blocked = false;
  double nearest = 0;
};

std::array<glm::dvec3, 3> triangle(const SegmentQuery& q, unsigned geom, unsigned prim) {
  const auto& pos = (*q.positions)[geom];
  const auto& idx = (*q.indices)[geom];
  return {glm::dvec3(pos[idx[3 * prim]]), glm::dvec3(pos[idx[3 * prim + 1]]), glm::dvec3(pos[idx[3 * prim + 2]])};
}

bool clear_callback(RTCPointQueryFunctionArguments* args) {
  auto& q = *static_cast<SegmentQuery*>(args->userPtr);
  const auto [a, b, c] = triangle(q, args->geomID, args->primID);
  if (segment_triangle_distance(q.a, q.b, a, b, c) >= q.clearance) return false;
  q.blocked = true;
  args->query->radius = 0.0f;  // one is enough: end the query
  return true;
}

bool nearest_callback(RTCPointQueryFunctionArguments* args) {
  auto& q = *static_cast<SegmentQuery*>(args->userPtr);
  const auto [a, b, c] = triangle(q, args->geomID, args->primID);
  if (std::max({a.y, b.y, c.y}) <= q.above_y) return false;
  const double d = point_triangle_distance(q.a, a, b, c);
  if (d >= q.nearest) return false;
  q.nearest = d;
  args->query->radius = static_cast<float>(d);
  return true;
}

}  // namespace

bool EmbreeScene::clear(const Vec3& a, const Vec3& b, float clearance) const {
  SegmentQuery q{&positions_, &indices_, glm::dvec3(a), glm::dvec3(b)};
  q.clearance = clearance;
  RTCPointQuery query{};
  const Vec3 mid = (a + b) * 0.5f;
  query.x = mid.x;
  query.y = mid.y;
  query.z = mid.z;
  // Every point of a triangle nearer than `clearance` to the segment lies within this sphere;
  // the margin covers float rounding of the centre and radius.
  query.radius = glm::length(b - a) * 0.5f + clearance * 1.001f + 1e-5f * (1.0f + glm::length(mid));
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(scene_, &query, &context, clear_callback, &q);
  return !q.blocked;
}

float EmbreeScene::distance_above(const Vec3& p, float limit, float above_y) const {
  SegmentQuery q{&positions_, &indices_, glm::dvec3(p), glm::dvec3(p)};
  q.above_y = above_y;
  q.nearest = limit;
  RTCPointQuery query{};
  query.x = p.x;
  query.y = p.y;
  query.z = p.z;
  query.radius = limit;
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(scene_, &query, &context, nearest_callback, &q);
  return static_cast<float>(q.nearest);
}

bool EmbreeScene::inside_any(const Vec3& p) const {
  std::array<ObjectId, 6> tested{};
  size_t count = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {1.0f, -1.0f}) {
      Vec3 dir(0.0f);
      dir[axis] = sign;
      const auto h = first_hit(p, dir, std::numeric_limits<float>::infinity());
      if (!h || std::find(tested.begin(), tested.begin() + count, *h) != tested.begin() + count) continue;
      tested[count++] = *h;
      if (inside(*h, p)) return true;
    }
  return false;
}

bool EmbreeScene::inside(ObjectId id, const Vec3& p) const {
  const Solid& s = solids_.at(id);
  return s.closed && visibility::solid_at(s.positions, s.indices, p, s.oriented);
}

bool EmbreeScene::box_is_solid(const Aabb& box) const {
  const Vec3 c = box.center();
  for (ObjectId id = 0; id < world_.object_count(); ++id) {
    const Aabb& b = world_.object(id).bounds;
    if (!solids_[id].closed || !(b.contains(box.min) && b.contains(box.max))) continue;
    bool all = inside(id, c);
    for (int k = 0; all && k < 8; ++k) {
      const Vec3 corner{k & 1 ? box.max.x : box.min.x, k & 2 ? box.max.y : box.min.y, k & 4 ? box.max.z : box.min.z};
      all = inside(id, corner + (c - corner) * 0.001f);
    }
    if (all) return true;
  }
  return false;
}

}  // namespace cellwalk::visibility
