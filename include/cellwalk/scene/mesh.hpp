// The scene model: a world is a set of objects; an object is an indexed triangle mesh with a
// bounding box, a stable id, a name and a colour.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "cellwalk/core/geometry.hpp"

namespace cellwalk {

using ObjectId = uint32_t;

// Colours are RGBA8 packed little-endian: r | g << 8 | b << 16 | a << 24.
using Rgba8 = uint32_t;
constexpr Rgba8 rgba8(uint8_t r, uint8_t g, uint8_t b, uint8_t a = 255) {
  return uint32_t(r) | uint32_t(g) << 8 | uint32_t(b) << 16 | uint32_t(a) << 24;
}

// The texture a mesh samples, when it samples none.
inline constexpr uint32_t kNoTexture = UINT32_MAX;

// An indexed triangle list. normals, colors and uvs are either empty or one per position.
struct Mesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;
  std::vector<Rgba8> colors;
  std::vector<Vec2> uvs;          // texture coordinates, (0, 0) the image's top-left corner
  std::vector<uint32_t> indices;  // three per triangle
  // The scene's base-colour texture (an index into its texture table, scene/texture.hpp) that
  // the uvs sample, multiplied by the vertex or object colour; kNoTexture for none.
  uint32_t texture = kNoTexture;

  size_t vertex_count() const { return positions.size(); }
  size_t triangle_count() const { return indices.size() / 3; }
  // Bytes the arrays hold, the measure budgets count.
  size_t byte_size() const;
};

struct Object {
  ObjectId id = 0;
  std::string name;
  Rgba8 color = rgba8(200, 200, 200);  // used where the mesh has no per-vertex colours
  Aabb bounds;
  Mesh mesh;
};

// Checks what every consumer relies on: a whole number of triangles, indices in range,
// positions finite and within ±kMaxCoordinate (check_position), finite normals and uvs,
// normals/colors/uvs empty or one per position, a texture only with uvs. Throws Error naming `where` and the vertex.
void validate(const Mesh& mesh, std::string_view where);

// Area-weighted vertex normals; replaces any normals present.
void compute_normals(Mesh& mesh);

Aabb bounds_of(const Mesh& mesh);

// Applies an affine transform to positions and (inverse-transpose) to normals; a singular
// transform's normals are recomputed from the transformed positions.
void transform(Mesh& mesh, const Mat4& m);

// Appends `src` to `dst`, offsetting indices. Normals/colours are kept only if both have them
// (an empty dst takes src's layout); uvs and the texture only if both sample the same one.
void append(Mesh& dst, const Mesh& src);

}  // namespace cellwalk
