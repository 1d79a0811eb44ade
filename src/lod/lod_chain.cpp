// Discrete LOD chains built with meshoptimizer, and the choice of a level by pixel error.
// Seeds: 000 HDoV thesis §5.6 (digest §3.10); 001 vLOD §2.2 (digest §3.2).
// Michael Garland and Paul S. Heckbert. Surface simplification using quadric error metrics.
// 1997 (meshopt_simplify). Jarek Rossignac and Paul Borrel. Multi-resolution 3D
// approximations for rendering complex scenes. 1993 (vertex clustering, meshopt's sloppy).
// Christer Ericson. Real-Time Collision Detection. 2005, §5.1.5 (closest point on triangle).
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "cellwalk/lod.hpp"

namespace cellwalk {
namespace {

const float* position_data(const Mesh& mesh) {
  return &mesh.positions[0].x;
}

// Closest point to p on triangle abc (Ericson §5.1.5), squared distance returned.
float point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  auto dist2 = [&](const Vec3& q) { return glm::dot(p - q, p - q); };
  if (d1 <= 0 && d2 <= 0) return dist2(a);
  const Vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dist2(b);
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return dist2(a + ab * (d1 / (d1 - d3)));
  const Vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dist2(c);
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return dist2(a + ac * (d2 / (d2 - d6)));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    return dist2(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
  }
  const float denom = 1.0f / (va + vb + vc);
  return dist2(a + ab * (vb * denom) + ac * (vc * denom));
}

// One-sided distance from evenly sampled original vertices to the simplified triangles
// (which index the original vertex array). Brute force: sloppy levels are small.
float sampled_distance(const Mesh& mesh, const std::vector<uint32_t>& indices, size_t samples) {
  const std::vector<Vec3>& v = mesh.positions;
  const size_t step = std::max<size_t>(1, v.size() / std::max<size_t>(1, samples));
  float worst2 = 0.0f;
  for (size_t i = 0; i < v.size(); i += step) {
    float best2 = std::numeric_limits<float>::infinity();
    for (size_t t = 0; t + 2 < indices.size() && best2 > worst2; t += 3) {
      best2 = std::min(best2, point_triangle_distance2(v[i], v[indices[t]], v[indices[t + 1]],
                                                       v[indices[t + 2]]));
    }
    // A level with no triangles leaves best2 infinite: the error is then unbounded.
    worst2 = std::max(worst2, best2);
  }
  return std::sqrt(worst2);
}

// The level made of `indices` (into mesh's vertices): cache-ordered triangles, vertices
// reordered by first use and compacted, attributes carried along.
Mesh optimised_level(const Mesh& mesh, std::vector<uint32_t> indices) {
  const size_t vertex_count = mesh.vertex_count();
  meshopt_optimizeVertexCache(indices.data(), indices.data(), indices.size(), vertex_count);
  std::vector<uint32_t> remap(vertex_count);
  const size_t unique =
      meshopt_optimizeVertexFetchRemap(remap.data(), indices.data(), indices.size(), vertex_count);
  Mesh level;
  level.indices.resize(indices.size());
  meshopt_remapIndexBuffer(level.indices.data(), indices.data(), indices.size(), remap.data());
  auto remap_stream = [&](const auto& src, auto& dst) {
    if (src.empty()) return;
    dst.resize(unique);
    meshopt_remapVertexBuffer(dst.data(), src.data(), vertex_count, sizeof(src[0]), remap.data());
  };
  remap_stream(mesh.positions, level.positions);
  remap_stream(mesh.normals, level.normals);
  remap_stream(mesh.colors, level.colors);
  return level;
}

struct Simplified {
  std::vector<uint32_t> indices;
  float error = 0.0f;  // absolute
  LodMethod method = LodMethod::kSimplify;
};

Simplified simplify_to(const Mesh& mesh, size_t target_triangles, size_t previous_triangles,
                       float scale, const LodParams& params) {
  const float* xyz = position_data(mesh);
  const size_t n = mesh.vertex_count();
  const float no_error_limit = std::numeric_limits<float>::max();
  Simplified s;
  s.indices.resize(mesh.indices.size());
  float relative = 0.0f;
  s.indices.resize(meshopt_simplify(s.indices.data(), mesh.indices.data(), mesh.indices.size(), xyz,
                                    n, sizeof(Vec3), target_triangles * 3, no_error_limit, 0,
                                    &relative));
  s.error = relative * scale;
  if (s.indices.size() / 3 <= params.stall_fraction * previous_triangles) return s;

  s.indices.resize(mesh.indices.size());
  s.indices.resize(meshopt_simplifySloppy(s.indices.data(), mesh.indices.data(),
                                          mesh.indices.size(), xyz, n, sizeof(Vec3),
                                          target_triangles * 3, no_error_limit, &relative));
  s.method = LodMethod::kSloppy;
  // meshopt's sloppy estimate is the grid's quadric error, not a distance bound: measure too.
  s.error = std::max(relative * scale, sampled_distance(mesh, s.indices, params.error_samples));
  return s;
}

}  // namespace

LodChain build_lod_chain(const Mesh& mesh, const LodParams& params) {
  LodChain chain;
  LodLevel first;
  first.mesh = optimised_level(mesh, mesh.indices);
  first.triangle_count = mesh.triangle_count();
  chain.levels.push_back(std::move(first));
  if (mesh.vertex_count() == 0) return chain;

  const float scale = meshopt_simplifyScale(position_data(mesh), mesh.vertex_count(), sizeof(Vec3));
  while (chain.levels.back().triangle_count > params.min_triangles) {
    const LodLevel& previous = chain.levels.back();
    const size_t target = std::max<size_t>(
        params.min_triangles, size_t(std::ceil(previous.triangle_count * params.ratio)));
    Simplified s = simplify_to(mesh, target, previous.triangle_count, scale, params);
    const size_t triangles = s.indices.size() / 3;
    if (triangles == 0 || triangles >= previous.triangle_count) break;  // no progress
    LodLevel level;
    level.triangle_count = triangles;
    level.error = std::max(s.error, previous.error);
    level.method = s.method;
    level.mesh = optimised_level(mesh, std::move(s.indices));
    chain.levels.push_back(std::move(level));
  }
  return chain;
}

size_t select_level(const LodChain& chain, float pixels_per_unit, float pixel_bound) {
  for (size_t i = chain.levels.size(); i-- > 1;) {
    // An infinite pixels_per_unit makes every positive error infinite: falls to level 0.
    if (chain.levels[i].error * pixels_per_unit <= pixel_bound) return i;
  }
  return 0;
}

}  // namespace cellwalk
