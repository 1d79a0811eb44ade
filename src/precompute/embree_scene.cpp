// The world's level-0 triangles in an Embree 3 scene: nearest-hit rays and point-in-mesh by
// ray parity (vLOD §5; HDoV thesis §5.5; solid view cells, docs/visibility.md).
#include "precompute/embree_scene.hpp"

#include <tbb/parallel_for.h>

#include <cstring>
#include <limits>
#include <mutex>

#include "cellwalk/core/error.hpp"

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

RTCGeometry make_geometry(RTCDevice device, const Mesh& mesh) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), mesh.vertex_count()));
  for (size_t i = 0; i < mesh.vertex_count(); ++i) std::memcpy(v + 3 * i, &mesh.positions[i], 3 * sizeof(float));
  auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                           3 * sizeof(uint32_t), mesh.triangle_count()));
  std::memcpy(t, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
  rtcCommitGeometry(g);
  return g;
}

}  // namespace

EmbreeScene::EmbreeScene(const World& world) : world_(world) {
  device_ = rtcNewDevice(nullptr);
  if (!device_) fail("embree", "cannot create a device (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  scene_ = rtcNewScene(device_);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
  std::mutex attach;
  tbb::parallel_for(size_t(0), world.object_count(), [&](size_t i) {
    const auto id = static_cast<ObjectId>(i);
    const Mesh mesh = world.decode_level(id, 0, world.read_level(id, 0));
    if (mesh.triangle_count() == 0) return;
    RTCGeometry g = make_geometry(device_, mesh);
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

bool EmbreeScene::inside(ObjectId id, const Vec3& p) const {
  // Slightly off-axis, so the ray is unlikely to graze the axis-aligned edges of boxes.
  const Vec3 dir = glm::normalize(Vec3(1.0f, 0.0137f, 0.0071f));
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  float t = 0.0f;
  int crossings = 0;
  for (int step = 0; step < 100000; ++step) {
    RTCRayHit rh = make_ray(p, dir, t, std::numeric_limits<float>::infinity());
    rtcIntersect1(scene_, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
    if (rh.hit.geomID == id) ++crossings;
    t = std::nextafter(rh.ray.tfar, std::numeric_limits<float>::infinity()) + 1e-5f * (1.0f + rh.ray.tfar);
  }
  return crossings % 2 == 1;
}

bool EmbreeScene::box_is_solid(const Aabb& box) const {
  const Vec3 c = box.center();
  for (ObjectId id = 0; id < world_.object_count(); ++id) {
    const Aabb& b = world_.object(id).bounds;
    if (!(b.contains(box.min) && b.contains(box.max))) continue;
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
