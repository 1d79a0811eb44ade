#include "cellwalk/scene/mesh.hpp"

#include <cmath>
#include <string>

#include "cellwalk/core/error.hpp"

namespace cellwalk {

size_t Mesh::byte_size() const {
  return positions.size() * sizeof(Vec3) + normals.size() * sizeof(Vec3) +
         colors.size() * sizeof(Rgba8) + uvs.size() * sizeof(Vec2) +
         indices.size() * sizeof(uint32_t);
}

void validate(const Mesh& mesh, std::string_view where) {
  if (mesh.indices.size() % 3 != 0)
    fail(where, "index count " + std::to_string(mesh.indices.size()) + " is not a multiple of 3");
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
    fail(where, "normal count differs from position count");
  if (!mesh.colors.empty() && mesh.colors.size() != mesh.positions.size())
    fail(where, "colour count differs from position count");
  if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
    fail(where, "texture coordinate count differs from position count");
  if (mesh.texture != kNoTexture && mesh.uvs.empty())
    fail(where, "samples texture " + std::to_string(mesh.texture) + " but has no texture coordinates");
  for (size_t i = 0; i < mesh.uvs.size(); ++i)
    if (!std::isfinite(mesh.uvs[i].x) || !std::isfinite(mesh.uvs[i].y))
      fail(where, "vertex " + std::to_string(i) + " has a non-finite texture coordinate");
  for (size_t i = 0; i < mesh.positions.size(); ++i) check_position(mesh.positions[i], where, "vertex " + std::to_string(i));
  for (size_t i = 0; i < mesh.normals.size(); ++i) {
    const Vec3& n = mesh.normals[i];
    if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z))
      fail(where, "vertex " + std::to_string(i) + " has a non-finite normal (" + std::to_string(n.x) + ", " +
                      std::to_string(n.y) + ", " + std::to_string(n.z) +
                      "); fix the normals, or remove them all so cellwalk computes them");
  }
  const size_t n = mesh.positions.size();
  for (size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= n)
      fail(where, "triangle " + std::to_string(i / 3) + " uses vertex " +
                      std::to_string(mesh.indices[i]) + " but there are only " +
                      std::to_string(n) + " vertices");
}

void compute_normals(Mesh& mesh) {
  mesh.normals.assign(mesh.positions.size(), Vec3(0.0f));
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    // The cross product's length is twice the area: area weighting comes for free.
    Vec3 n = glm::cross(mesh.positions[b] - mesh.positions[a], mesh.positions[c] - mesh.positions[a]);
    mesh.normals[a] += n;
    mesh.normals[b] += n;
    mesh.normals[c] += n;
  }
  for (Vec3& n : mesh.normals) {
    float len = glm::length(n);
    n = len > 0.0f ? n / len : Vec3(0.0f, 1.0f, 0.0f);
  }
}

Aabb bounds_of(const Mesh& mesh) {
  Aabb box;
  for (const Vec3& p : mesh.positions) box.extend(p);
  return box;
}

void transform(Mesh& mesh, const Mat4& m) {
  for (Vec3& p : mesh.positions) p = Vec3(m * Vec4(p, 1.0f));
  if (mesh.normals.empty()) return;
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(m)));
  // A singular m (a zero scale, which exporters use to hide a node) has no inverse: normals
  // carried through it would be NaN, so they follow from the flattened positions instead.
  for (int c = 0; c < 3; ++c)
    if (!std::isfinite(normal_matrix[c].x) || !std::isfinite(normal_matrix[c].y) || !std::isfinite(normal_matrix[c].z))
      return compute_normals(mesh);
  for (Vec3& n : mesh.normals) {
    n = normal_matrix * n;
    float len = glm::length(n);
    if (len > 0.0f) n /= len;
  }
}

void append(Mesh& dst, const Mesh& src) {
  const bool first = dst.positions.empty();
  const bool keep_normals = first ? !src.normals.empty() : (!dst.normals.empty() && !src.normals.empty());
  const bool keep_colors = first ? !src.colors.empty() : (!dst.colors.empty() && !src.colors.empty());
  const bool keep_uvs = first ? !src.uvs.empty()
                              : (!dst.uvs.empty() && !src.uvs.empty() && dst.texture == src.texture);
  const uint32_t base = static_cast<uint32_t>(dst.positions.size());
  dst.positions.insert(dst.positions.end(), src.positions.begin(), src.positions.end());
  if (keep_normals) dst.normals.insert(dst.normals.end(), src.normals.begin(), src.normals.end());
  else dst.normals.clear();
  if (keep_colors) dst.colors.insert(dst.colors.end(), src.colors.begin(), src.colors.end());
  else dst.colors.clear();
  if (keep_uvs) {
    dst.uvs.insert(dst.uvs.end(), src.uvs.begin(), src.uvs.end());
    dst.texture = src.texture;
  } else {
    dst.uvs.clear();
    dst.texture = kNoTexture;
  }
  dst.indices.reserve(dst.indices.size() + src.indices.size());
  for (uint32_t i : src.indices) dst.indices.push_back(base + i);
}

}  // namespace cellwalk
