#include "scene/shapes.hpp"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "cellwalk/core/error.hpp"

namespace cellwalk::shapes {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr uint32_t kNone = UINT32_MAX;

enum class Band { kDegenerate, kCapAtStart, kCapAtEnd, kApexAtStart, kApexAtEnd, kQuad };

Band classify(Vec2 a, Vec2 b, bool whole) {
  const bool a_axis = a.x <= 0.0f, b_axis = b.x <= 0.0f;
  if (a_axis && b_axis) return Band::kDegenerate;
  if (!a_axis && !b_axis) return Band::kQuad;
  // A flat disc needs no centre vertex: a fan over the rim covers it with n − 2 triangles.
  if (whole && a.y == b.y) return a_axis ? Band::kCapAtStart : Band::kCapAtEnd;
  return a_axis ? Band::kApexAtStart : Band::kApexAtEnd;
}

// Hands out vertex indices for (profile point, sector). Smooth surfaces share one ring per
// point so compute_normals() averages across sectors and bands; faceted ones get fresh
// vertices per face (reset() between faces) so each face keeps its own flat normal.
class Vertices {
 public:
  Vertices(Mesh& mesh, const Polyline& line, const Revolution& how, bool whole)
      : mesh_(mesh),
        line_(line),
        how_(how),
        ring_size_(whole ? how.sectors : how.sectors + 1),
        rings_(line.points.size(), kNone) {}

  uint32_t at(size_t point, int sector) {
    if (how_.faceted) return faceted(point, sector);
    if (rings_[point] == kNone) {
      rings_[point] = static_cast<uint32_t>(mesh_.positions.size());
      for (int k = 0; k < ring_size_; ++k) mesh_.positions.push_back(position(point, k));
    }
    return rings_[point] + static_cast<uint32_t>(sector % ring_size_);
  }
  void reset() { face_.clear(); }

 private:
  struct Key {
    size_t point;
    int sector;
    uint32_t index;
  };
  uint32_t faceted(size_t point, int sector) {
    for (const Key& k : face_)
      if (k.point == point && k.sector == sector) return k.index;
    const uint32_t index = static_cast<uint32_t>(mesh_.positions.size());
    mesh_.positions.push_back(position(point, sector));
    face_.push_back({point, sector, index});
    return index;
  }
  Vec3 position(size_t point, int sector) const {
    const Vec2 p = line_.points[point];
    const float a = how_.phase + how_.sweep * static_cast<float>(sector) / how_.sectors;
    return {p.x * std::cos(a), p.y, p.x * std::sin(a)};
  }

  Mesh& mesh_;
  const Polyline& line_;
  const Revolution& how_;
  int ring_size_;
  std::vector<uint32_t> rings_;
  std::vector<Key> face_;
};

void triangle(Mesh& mesh, uint32_t a, uint32_t b, uint32_t c) {
  mesh.indices.insert(mesh.indices.end(), {a, b, c});
}

// A disc on the ring of `point`; `upward` when the profile walks inwards (a top cap).
void cap(Mesh& mesh, Vertices& v, size_t point, int n, bool upward) {
  v.reset();
  for (int k = 1; k + 1 < n; ++k) {
    if (upward)
      triangle(mesh, v.at(point, 0), v.at(point, k + 1), v.at(point, k));
    else
      triangle(mesh, v.at(point, 0), v.at(point, k), v.at(point, k + 1));
  }
}

void band(Mesh& mesh, Vertices& v, size_t p0, size_t p1, Band kind, int n) {
  if (kind == Band::kCapAtStart) return cap(mesh, v, p1, n, false);
  if (kind == Band::kCapAtEnd) return cap(mesh, v, p0, n, true);
  for (int k = 0; k < n; ++k) {
    v.reset();
    // Quad (a0 a1 along p0's ring, b0 b1 along p1's): (a0 b0 b1) and (a0 b1 a1) face outwards
    // when the solid lies left of the profile. An apex drops the triangle that collapses.
    if (kind != Band::kApexAtEnd) triangle(mesh, v.at(p0, k), v.at(p1, k), v.at(p1, k + 1));
    if (kind != Band::kApexAtStart) triangle(mesh, v.at(p0, k), v.at(p1, k + 1), v.at(p0, k + 1));
  }
}

Polyline line(std::initializer_list<Vec2> points) {
  return Polyline{points, false};
}

}  // namespace

Mesh revolve(std::span<const Polyline> profile, const Revolution& how) {
  if (how.sectors < 3) fail("shapes::revolve", "needs at least 3 sectors");
  const bool whole = how.sweep >= 2.0f * kPi - 1e-5f;
  Mesh mesh;
  for (const Polyline& line : profile) {
    const size_t count = line.points.size();
    if (count < 2) continue;
    Vertices vertices(mesh, line, how, whole);
    const size_t bands = line.closed ? count : count - 1;
    for (size_t b = 0; b < bands; ++b) {
      const size_t p0 = b, p1 = (b + 1) % count;
      const Band kind = classify(line.points[p0], line.points[p1], whole);
      if (kind != Band::kDegenerate) band(mesh, vertices, p0, p1, kind, how.sectors);
    }
  }
  compute_normals(mesh);
  return mesh;
}

Mesh box(Vec3 size) {
  // A square prism of 4 faceted sectors turned 45°: corners at (±½, ±½).
  const float r = std::numbers::sqrt2_v<float> * 0.5f;
  const Polyline profile[] = {line({{0, 0}, {r, 0}}), line({{r, 0}, {r, 1}}),
                              line({{r, 1}, {0, 1}})};
  Mesh mesh = revolve(profile, {.sectors = 4, .phase = kPi / 4, .faceted = true});
  transform(mesh, glm::scale(Mat4(1.0f), size));
  return mesh;
}

Mesh cylinder(float radius, float height, int sectors, bool capped) {
  const Polyline side = line({{radius, 0}, {radius, height}});
  if (!capped) return revolve({&side, 1}, {.sectors = sectors});
  const Polyline profile[] = {line({{0, 0}, {radius, 0}}), side,
                              line({{radius, height}, {0, height}})};
  return revolve(profile, {.sectors = sectors});
}

Mesh cone(float radius, float height, int sectors) {
  const Polyline profile[] = {line({{0, 0}, {radius, 0}}), line({{radius, 0}, {0, height}})};
  return revolve(profile, {.sectors = sectors});
}

Mesh pyramid(Vec3 size) {
  const float r = std::numbers::sqrt2_v<float> * 0.5f;
  const Polyline profile[] = {line({{0, 0}, {r, 0}}), line({{r, 0}, {0, 1}})};
  Mesh mesh = revolve(profile, {.sectors = 4, .phase = kPi / 4, .faceted = true});
  transform(mesh, glm::scale(Mat4(1.0f), size));
  return mesh;
}

Mesh ellipsoid(Vec3 radii, int sectors, int rings) {
  Polyline meridian;
  for (int i = 0; i <= rings; ++i) {
    const float phi = -kPi / 2 + kPi * static_cast<float>(i) / rings;
    meridian.points.push_back({i == 0 || i == rings ? 0.0f : std::cos(phi), 1.0f + std::sin(phi)});
  }
  Mesh mesh = revolve({&meridian, 1}, {.sectors = sectors});
  transform(mesh, glm::scale(Mat4(1.0f), radii));
  return mesh;
}

Mesh torus(float major_radius, float tube_radius, int sectors, int sides, float sweep) {
  Polyline circle{{}, true};
  for (int j = 0; j < sides; ++j) {
    const float phi = 2.0f * kPi * static_cast<float>(j) / sides;
    circle.points.push_back(
        {major_radius + tube_radius * std::cos(phi), tube_radius * std::sin(phi)});
  }
  return revolve({&circle, 1}, {.sectors = sectors, .sweep = sweep});
}

void Assembly::add(Mesh part, const Mat4& m) {
  transform(part, m);
  append(mesh_, part);
}

Mat4 Assembly::translate(Vec3 t) {
  return glm::translate(Mat4(1.0f), t);
}

Mat4 place(Vec3 translation, float yaw, Vec3 scale) {
  Mat4 m = glm::translate(Mat4(1.0f), translation);
  m = glm::rotate(m, yaw, Vec3(0, 1, 0));
  return glm::scale(m, scale);
}

void paint(Mesh& mesh, Rgba8 color) {
  mesh.colors.assign(mesh.positions.size(), color);
}

Mesh unit_model(std::vector<Object> objects, const std::string& where) {
  Mesh merged;
  for (Object& o : objects) append(merged, o.mesh);
  // Generated scenes carry no texture table: a model placed by a generator is drawn in colour.
  merged.uvs.clear();
  merged.texture = kNoTexture;
  if (merged.triangle_count() == 0) fail(where, "the model has no triangles");
  if (merged.normals.empty()) compute_normals(merged);
  const Aabb box = bounds_of(merged);
  const Vec3 size = box.size();
  const float largest = std::max({size.x, size.y, size.z});
  if (!(largest > 0.0f)) fail(where, "the model has no extent");
  Mat4 m = glm::scale(Mat4(1.0f), Vec3(1.0f / largest));
  m = glm::translate(m, Vec3(-box.center().x, -box.min.y, -box.center().z));
  transform(merged, m);
  return merged;
}

void ObjectEmitter::emit(std::string_view name, Rgba8 color, Mesh& mesh) {
  object_.id = next_id_++;
  object_.name.assign(name);
  object_.color = color;
  // Swap rather than copy: the caller's buffers come back to be refilled for the next object.
  std::swap(object_.mesh, mesh);
  object_.bounds = bounds_of(object_.mesh);
  info_.bounds.extend(object_.bounds);
  sink_.add(object_);
}

}  // namespace cellwalk::shapes
