// Discrete LOD chains built with meshoptimizer, and the choice of a level by pixel error.
// Seeds: 000 HDoV thesis §5.6 (digest §3.10); 001 vLOD §2.2 (digest §3.2).
// Michael Garland and Paul S. Heckbert. Surface simplification using quadric error metrics.
// 1997 (meshopt_simplify). Jarek Rossignac and Paul Borrel. Multi-resolution 3D
// approximations for rendering complex scenes. 1993 (vertex clustering, meshopt's sloppy).
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "cellwalk/lod.hpp"
#include "lod/surface_distance.hpp"

namespace cellwalk {
namespace {

const float* position_data(const Mesh& mesh) {
  return &mesh.positions[0].x;
}

// The original vertices whose distance to every level is measured (all of them up to
// params.error_samples, else that many evenly spaced by index).
std::vector<Vec3> original_samples(const Mesh& original, size_t samples) {
  const std::vector<Vec3>& v = original.positions;
  if (v.size() <= samples) return v;
  std::vector<Vec3> out;
  out.reserve(samples);
  for (size_t i = 0; i < samples; ++i) out.push_back(v[i * v.size() / samples]);
  return out;
}

// Points of the level whose distance to the original is measured: its triangles'
// centroids. Its vertices need no measuring: both simplifiers keep a subset of the source's
// vertices, unmoved, so every level's vertices are original vertices (distance 0).
std::vector<Vec3> level_samples(const Mesh& level) {
  std::vector<Vec3> out;
  out.reserve(level.triangle_count());
  for (size_t t = 0; t < level.indices.size(); t += 3) {
    out.push_back((level.positions[level.indices[t]] + level.positions[level.indices[t + 1]] +
                   level.positions[level.indices[t + 2]]) /
                  3.0f);
  }
  return out;
}

// The original as measured against: its triangles in a grid and its sampled vertices.
struct Original {
  TriangleGrid triangles;
  std::vector<Vec3> samples;
};

// REQUIRES: `mesh` is compacted (level 0), so that only vertices in use are sampled.
Original original_of(const Mesh& mesh, size_t samples) {
  return {TriangleGrid(mesh.positions, mesh.indices), original_samples(mesh, samples)};
}

// max(floor, distance from the sampled original vertices to the level's triangles,
// distance from the level's sample points to the original's triangles).
float measured_error(const Original& original, const Mesh& level, float floor) {
  const TriangleGrid level_triangles(level.positions, level.indices);
  float worst2 = max_nearest2(level_triangles, original.samples, floor * floor);
  worst2 = max_nearest2(original.triangles, level_samples(level), worst2);
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
  std::vector<uint32_t> indices;  // into the source mesh's vertices
  float error = 0.0f;             // meshopt's estimate against the source, absolute
  LodMethod method = LodMethod::kSimplify;
};

// `source` (the previous level) simplified towards target_triangles: meshopt_simplify, or
// meshopt_simplifySloppy when that keeps more than stall_fraction of the source.
Simplified simplify_to(const Mesh& source, size_t target_triangles, const LodParams& params) {
  const float* xyz = position_data(source);
  const size_t n = source.vertex_count();
  const float scale = meshopt_simplifyScale(xyz, n, sizeof(Vec3));
  const float no_error_limit = std::numeric_limits<float>::max();
  Simplified s;
  s.indices.resize(source.indices.size());
  float relative = 0.0f;
  s.indices.resize(meshopt_simplify(s.indices.data(), source.indices.data(), source.indices.size(),
                                    xyz, n, sizeof(Vec3), target_triangles * 3, no_error_limit, 0,
                                    &relative));
  s.error = relative * scale;
  if (s.indices.size() / 3 <= params.stall_fraction * source.triangle_count()) return s;

  s.indices.resize(source.indices.size());
  s.indices.resize(meshopt_simplifySloppy(s.indices.data(), source.indices.data(),
                                          source.indices.size(), xyz, n, sizeof(Vec3),
                                          target_triangles * 3, no_error_limit, &relative));
  s.error = relative * scale;
  s.method = LodMethod::kSloppy;
  return s;
}

}  // namespace

LodChain build_lod_chain(const Mesh& mesh, const LodParams& params) {
  LodChain chain;
  LodLevel first;
  first.mesh = optimised_level(mesh, mesh.indices);
  first.triangle_count = mesh.triangle_count();
  chain.levels.push_back(std::move(first));
  if (chain.levels[0].triangle_count <= params.min_triangles) return chain;

  const Original original = original_of(chain.levels[0].mesh, params.error_samples);
  while (chain.levels.back().triangle_count > params.min_triangles) {
    const LodLevel& previous = chain.levels.back();
    const size_t target = std::max<size_t>(
        params.min_triangles, size_t(std::ceil(previous.triangle_count * params.ratio)));
    Simplified s = simplify_to(previous.mesh, target, params);
    const size_t triangles = s.indices.size() / 3;
    if (triangles == 0 || triangles >= previous.triangle_count) break;  // no progress
    LodLevel level;
    level.triangle_count = triangles;
    level.method = s.method;
    level.mesh = optimised_level(previous.mesh, std::move(s.indices));
    // Measured against the original, not the previous level: errors do not accumulate.
    level.error = measured_error(original, level.mesh, std::max(s.error, previous.error));
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
