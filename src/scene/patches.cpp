// Splitting a large mesh into spatial patches, so that one big scan is many objects that
// culling and LOD can each take or leave (issue 16; Nexus splits its models into patches the
// same way). Recursive median splits of the triangles' centroids along the longest axis of
// their bounds: every patch is compact, the patches partition the triangles, and sizes stay
// between half the bound and the bound.
#include <algorithm>
#include <numeric>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"

namespace cellwalk {

namespace {

Vec3 centroid(const Mesh& mesh, uint32_t t) {
  return (mesh.positions[mesh.indices[3 * t]] + mesh.positions[mesh.indices[3 * t + 1]] +
          mesh.positions[mesh.indices[3 * t + 2]]) / 3.0f;
}

// Orders triangles[begin, end) so that each run of at most max_triangles is one patch;
// appends each run's end to `ends`.
void split(const std::vector<Vec3>& centroids, std::vector<uint32_t>& triangles, size_t begin, size_t end,
           size_t max_triangles, std::vector<size_t>& ends) {
  // An explicit stack: a degenerate mesh must not recurse deep.
  std::vector<std::pair<size_t, size_t>> todo = {{begin, end}};
  while (!todo.empty()) {
    auto [b, e] = todo.back();
    todo.pop_back();
    if (e - b <= max_triangles) {
      ends.push_back(e);
      continue;
    }
    Aabb box;
    for (size_t i = b; i < e; ++i) box.extend(centroids[triangles[i]]);
    const Vec3 size = box.size();
    const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
    const size_t mid = b + (e - b) / 2;
    std::nth_element(triangles.begin() + b, triangles.begin() + mid, triangles.begin() + e,
                     [&](uint32_t l, uint32_t r) { return centroids[l][axis] < centroids[r][axis]; });
    // Depth first, left half first: patches come out in spatial order.
    todo.emplace_back(mid, e);
    todo.emplace_back(b, mid);
  }
}

Mesh patch_of(const Mesh& mesh, std::span<const uint32_t> triangles) {
  Mesh out;
  out.texture = mesh.texture;
  std::unordered_map<uint32_t, uint32_t> vertex_of;
  vertex_of.reserve(triangles.size() * 2);
  for (uint32_t t : triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.indices[3 * t + k];
      auto [it, added] = vertex_of.emplace(v, uint32_t(out.positions.size()));
      if (added) {
        out.positions.push_back(mesh.positions[v]);
        if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[v]);
        if (!mesh.colors.empty()) out.colors.push_back(mesh.colors[v]);
        if (!mesh.uvs.empty()) out.uvs.push_back(mesh.uvs[v]);
      }
      out.indices.push_back(it->second);
    }
  }
  return out;
}

}  // namespace

std::vector<Object> split_into_patches(Object object, size_t max_triangles) {
  if (max_triangles == 0) fail("split_into_patches", "a patch needs room for at least one triangle");
  const size_t n = object.mesh.triangle_count();
  std::vector<Object> out;
  if (n <= max_triangles) {
    out.push_back(std::move(object));
    return out;
  }
  std::vector<Vec3> centroids(n);
  for (size_t t = 0; t < n; ++t) centroids[t] = centroid(object.mesh, uint32_t(t));
  std::vector<uint32_t> triangles(n);
  std::iota(triangles.begin(), triangles.end(), 0u);
  std::vector<size_t> ends;
  split(centroids, triangles, 0, n, max_triangles, ends);
  size_t begin = 0;
  for (size_t end : ends) {
    Object patch;
    patch.id = object.id;
    patch.name = object.name + "#" + std::to_string(out.size());
    patch.color = object.color;
    patch.mesh = patch_of(object.mesh, std::span(triangles).subspan(begin, end - begin));
    patch.bounds = bounds_of(patch.mesh);
    out.push_back(std::move(patch));
    begin = end;
  }
  return out;
}

Mat4 placement_matrix(const Placement& p) {
  // z up to y up: (x, y, z) -> (x, z, -y), a rotation (handedness and winding are kept).
  const Mat4 up = p.z_up ? Mat4(Vec4(1, 0, 0, 0), Vec4(0, 0, -1, 0), Vec4(0, 1, 0, 0), Vec4(0, 0, 0, 1)) : Mat4(1.0f);
  return glm::translate(Mat4(1.0f), p.offset) * glm::scale(Mat4(1.0f), Vec3(p.scale)) * up;
}

void place(Object& object, const Mat4& m) {
  transform(object.mesh, m);
  object.bounds = bounds_of(object.mesh);
}

}  // namespace cellwalk
