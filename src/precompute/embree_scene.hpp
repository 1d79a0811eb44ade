// The world's full-detail triangles (level 0 of every object) in one Embree scene, for the
// sampling engine's rays (vLOD §5 samples visibility; HDoV thesis §5.5 renders it), the
// point-in-solid test that marks view cells inside objects, and the clearance queries of the
// path planner (path_planner.cpp).
#pragma once

#include <embree3/rtcore.h>

#include <optional>
#include <span>
#include <vector>

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

  // Rays sharing one origin, cast as a coherent stream: ids[i] = 1 + the first object hit along
  // origin + t·dirs[i] for t in [near, far], 0 if none. t is in units of |dirs[i]|, so a
  // direction whose component along a view axis is 1 clips at view depths near and far, as a
  // GL projection does. REQUIRES ids.size() == dirs.size().
  void first_hits(const Vec3& origin, std::span<const Vec3> dirs, float near, float far, std::span<uint32_t> ids) const;

  // A ray's first hit: its distance along the (unit) direction, the object, and the hit
  // triangle's unit normal (as wound: a double-sided surface may give either side's).
  struct Hit {
    float t = 0;
    ObjectId id = 0;
    Vec3 normal{0.0f};
  };
  // The first hit along origin + t·dir for t in [near, far]. REQUIRES |dir| = 1.
  std::optional<Hit> hit(const Vec3& origin, const Vec3& dir, float near, float far) const;

  // Whether every point of the segment [a, b] (a point when a == b) lies at least `clearance`
  // from every triangle, measured exactly in double precision (point query over the triangles
  // near the segment, then segment–triangle distances).
  bool clear(const Vec3& a, const Vec3& b, float clearance) const;

  // The distance from p to the nearest triangle with a vertex above height `above_y`, or
  // `limit` when none is nearer.
  float distance_above(const Vec3& p, float limit, float above_y) const;

  // Whether p is provably inside some closed object: inside() for each object hit first by a
  // ray from p along ±x, ±y, ±z. An object that holds another one between p and its own
  // surface in all six directions is missed.
  bool inside_any(const Vec3& p) const;

  // Whether p is provably inside the solid object `id`'s mesh bounds: the mesh is closed
  // (is_closed) and visibility::solid_at says so, by winding number when the mesh is oriented,
  // else by parity, along six rays that must agree. Never for an open mesh (a plane, a slanted
  // wall) or a double-sided one (winding number 0); a point on the surface is not inside.
  bool inside(ObjectId id, const Vec3& p) const;

  // A view cell is solid when its box lies within one object's bounding box and its centre and
  // 8 corners (pulled 0.1 % inwards, off the shared faces) are all inside that object's mesh.
  // Exact for convex objects; a concave object may hide a pocket the 9 points miss.
  bool box_is_solid(const Aabb& box) const;

 private:
  // An object's triangles as Embree holds them (no second copy), and what its solid is.
  struct Solid {
    std::span<const Vec3> positions;
    std::span<const uint32_t> indices;
    bool closed = false;    // visibility::is_closed: crossings define a solid
    bool oriented = false;  // visibility::is_oriented: by winding number, else by parity
  };

  const World& world_;
  std::vector<Solid> solids_;  // per object
  // The same spans again, by geometry id, as the point-query callbacks read them.
  std::vector<std::span<const Vec3>> positions_;
  std::vector<std::span<const uint32_t>> indices_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

}  // namespace cellwalk::visibility
