// The world's full-detail triangles (level 0 of every object) in one Embree scene, for the
// sampling engine's rays (vLOD §5 samples visibility; HDoV thesis §5.5 renders it) and the
// point-in-solid test that marks view cells inside objects.
#pragma once

#include <embree3/rtcore.h>

#include <optional>

#include "cellwalk/store/world.hpp"

namespace cellwalk::visibility {

// Holds every object's level-0 mesh in Embree's memory (precomputation only: it is not
// bounded by a run's budget). Geometry id = ObjectId. Thread-safety: const methods may be
// called concurrently.
class EmbreeScene {
 public:
  explicit EmbreeScene(const World& world);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  // The first object hit along origin + t·dir for t in (0, far), nullopt if none.
  std::optional<ObjectId> first_hit(const Vec3& origin, const Vec3& dir, float far) const;

  // Whether p is inside object `id`'s mesh: a ray's crossings with that mesh are odd. Meaningful
  // for closed meshes; a point on the surface may go either way.
  bool inside(ObjectId id, const Vec3& p) const;

  // A view cell is solid when its box lies within one object's bounding box and its centre and
  // 8 corners (pulled 0.1 % inwards, off the shared faces) are all inside that object's mesh.
  // Exact for convex objects; a concave object may hide a pocket the 9 points miss.
  bool box_is_solid(const Aabb& box) const;

 private:
  const World& world_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

}  // namespace cellwalk::visibility
