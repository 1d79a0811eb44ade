// Primitive shapes for the generators, all made by one mechanism: revolving a profile in the
// (radius, height) half-plane about the Y axis. A box is a 4-sector faceted revolution, a cone
// a profile ending on the axis, a pipe elbow a partial revolution of a circle. Every mesh has
// area-weighted normals, outward-facing counter-clockwise triangles and no per-vertex colours
// unless painted. Shapes stand on y = 0 (the torus is centred on the origin), on the Y axis;
// callers place them with place() or an Assembly.
#pragma once

#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/core/geometry.hpp"
#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/scene/scene.hpp"

namespace cellwalk::shapes {

// A polyline in the (r, y) half-plane (r >= 0). Consecutive polylines meet at a crease (their
// vertices are not shared); within one polyline normals are smooth. Order the points so the
// solid lies to the left when walking along the profile (bottom centre → rim → top centre):
// that makes the triangles face outwards.
struct Polyline {
  std::vector<Vec2> points;
  bool closed = false;  // last point joins the first (a torus's circle)
};

struct Revolution {
  int sectors = 16;                                // angular segments
  float phase = 0.0f;                              // angle of the first sector boundary, radians
  float sweep = 2.0f * std::numbers::pi_v<float>;  // < 2π leaves the ends open (elbows)
  bool faceted = false;  // flat-shaded sectors (boxes, pyramids) instead of smooth
};

// Revolves `profile` about the Y axis. A band that closes on the axis at constant height is a
// flat cap of (sectors − 2) triangles when the sweep is whole; one that reaches the axis at
// another height ends in an apex of `sectors` triangles; any other band is 2 × sectors.
// REQUIRES: sectors >= 3; r >= 0 for every point.
Mesh revolve(std::span<const Polyline> profile, const Revolution& how);

// Axis-aligned box of the given size standing on y = 0 (12 triangles).
Mesh box(Vec3 size);
// Capped cylinder (4n − 4 triangles), or open tube when !capped (2n).
Mesh cylinder(float radius, float height, int sectors, bool capped = true);
// Cone with its base on y = 0 (2n − 2 triangles).
Mesh cone(float radius, float height, int sectors);
// Square-based pyramid, base size × size on y = 0 (6 triangles).
Mesh pyramid(Vec3 size);
// Ellipsoid with semi-axes `radii`, its lowest point on y = 0 (2n(rings − 1) triangles).
Mesh ellipsoid(Vec3 radii, int sectors, int rings);
// Torus about the Y axis, centred on the origin (2 × sectors × sides triangles). A sweep
// below 2π gives a pipe bend: the arc runs from +X towards +Z, its ends left open.
Mesh torus(float major_radius, float tube_radius, int sectors, int sides,
           float sweep = 2.0f * std::numbers::pi_v<float>);

// Builds composite models: transformed parts appended to one mesh.
class Assembly {
 public:
  // Appends `part` after applying `m`. Parts must all be painted or all unpainted.
  void add(Mesh part, const Mat4& m);
  void add(Mesh part, Vec3 translation) { add(std::move(part), translate(translation)); }
  Mesh take() { return std::move(mesh_); }

  static Mat4 translate(Vec3 t);

 private:
  Mesh mesh_;
};

// translate(t) · rotate_y(yaw) · scale(s): how every generator places a model.
Mat4 place(Vec3 translation, float yaw, Vec3 scale = Vec3(1.0f));

// Sets every vertex colour to `color` (for models whose parts differ in colour).
void paint(Mesh& mesh, Rgba8 color);

// Merges all objects' meshes into one and moves it so it stands on y = 0, centred on the
// Y axis, with its largest extent equal to 1. Throws Error naming `where` if it is empty.
Mesh unit_model(std::vector<Object> objects, const std::string& where);

// Hands generated meshes to a sink as Objects: ids dense from 0 in order, bounds computed,
// SceneInfo::bounds extended. Holds one Object whose buffers are reused, nothing else.
class ObjectEmitter {
 public:
  ObjectEmitter(ObjectSink& sink, SceneInfo& info) : sink_(sink), info_(info) {}
  // Emits `mesh` (left in a valid, unspecified state) as the next object.
  void emit(std::string_view name, Rgba8 color, Mesh& mesh);
  uint64_t count() const { return next_id_; }

 private:
  ObjectSink& sink_;
  SceneInfo& info_;
  Object object_;
  ObjectId next_id_ = 0;
};

}  // namespace cellwalk::shapes
