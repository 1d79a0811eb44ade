// Discrete LOD chains built with meshoptimizer, and the choice of a level by pixel error.
// Seeds: 000 HDoV thesis §5.6 (digest §3.10); 001 vLOD §2.2 (digest §3.2).
// Michael Garland and Paul S. Heckbert. Surface simplification using quadric error metrics.
// 1997 (meshopt_simplify). Jarek Rossignac and Paul Borrel. Multi-resolution 3D
// approximations for rendering complex scenes. 1993 (vertex clustering, meshopt's sloppy).
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "cellwalk/lod/lod.hpp"
#include "lod/surface_distance.hpp"

namespace cellwalk {
namespace {

const float* position_data(const Mesh& mesh) {
  return &mesh.positions[0].x;
}

// The level-0 vertices whose distance to every level is measured: all of them up to
// `samples`, else that many evenly spaced by index.
std::vector<uint32_t> original_samples(size_t vertex_count, size_t samples) {
  std::vector<uint32_t> out(std::min(vertex_count, samples));
  for (size_t i = 0; i < out.size(); ++i) out[i] = uint32_t(i * vertex_count / out.size());
  return out;
}

// Points of the level whose distance to the original is measured: on each triangle, the
// barycentric grid of n + 1 points a side less its corners (the centroid when n = 1), n the
// longest edge over `spacing`, at most kMaxSubdivisions. Its vertices need no measuring: both
// simplifiers return indices into their source's vertices, so every level's vertices are
// original vertices (distance 0). Centroids alone miss the middle of long, thin triangles (the
// walls and roofs of coarse buildings): points between them lay up to 1.37× farther than
// recorded on the demo's city, and a level chosen for under a pixel erred by more.
constexpr int kMaxSubdivisions = 32;

std::vector<Vec3> level_samples(const Mesh& level, float spacing) {
  std::vector<Vec3> out;
  out.reserve(level.triangle_count());
  for (size_t t = 0; t < level.indices.size(); t += 3) {
    const Vec3 a = level.positions[level.indices[t]], b = level.positions[level.indices[t + 1]],
               c = level.positions[level.indices[t + 2]];
    const float longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    const int n = spacing > 0.0f ? std::clamp(int(std::ceil(longest / spacing)), 1, kMaxSubdivisions) : 1;
    if (n == 1) {
      out.push_back((a + b + c) / 3.0f);
      continue;
    }
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const int k = n - i - j;
        if (i == n || j == n || k == n) continue;  // a corner: an original vertex
        out.push_back((float(i) * a + float(j) * b + float(k) * c) / float(n));
      }
  }
  return out;
}

// The original (level 0) as measured against: its triangles in a grid, its vertices and
// which of them are sampled, and points of its surface between the vertices.
struct Original {
  TriangleGrid triangles;
  std::vector<Vec3> positions;
  std::vector<uint32_t> samples;
  float spacing = 0.0f;  // of the points measured on a level's triangles: 1/64 of the diagonal
  // The same grid on the original's triangles (at most `samples` of them, evenly spaced):
  // vertices alone miss a part the level dropped whose vertices all lie near what it kept (a
  // ladder's rungs, a centimetre from its rails: recorded 0.02 m, the rungs' middles 0.225 m
  // from the level).
  std::vector<Vec3> surface;
};

std::vector<Vec3> evenly_spaced(std::vector<Vec3> points, size_t most) {
  if (points.size() <= most) return points;
  std::vector<Vec3> out(most);
  for (size_t i = 0; i < most; ++i) out[i] = points[i * points.size() / most];
  return out;
}

// The original's grid is 8× finer than the levels': its points are measured once for every
// level, and a dropped part's farthest point lies between them (a ladder's rung is 0.5 m of a
// 10 m ladder: at 1/64 of the diagonal the rung's middle fell between points, 0.14 m recorded
// for 0.225).
constexpr float kOriginalGridRefinement = 8.0f;

Original original_of(const Mesh& level0, size_t samples) {
  const float spacing = glm::length(bounds_of(level0).size()) / 64.0f;
  return {TriangleGrid(level0.positions, level0.indices), level0.positions,
          original_samples(level0.vertex_count(), samples), spacing,
          evenly_spaced(level_samples(level0, spacing / kOriginalGridRefinement), samples)};
}

// A level as built: its mesh and, per vertex, that vertex's index in level 0.
struct BuiltLevel {
  Mesh mesh;
  std::vector<uint32_t> original_ids;
};

// max(floor, distance from the sampled original vertices and surface points to the level's
// triangles, distance from the level's surface points to the original's triangles). Sampled
// vertices that the level kept are skipped: they lie on it (surface points may not).
float measured_error(const Original& original, const BuiltLevel& level, float floor) {
  std::vector<uint8_t> kept(original.positions.size(), 0);
  for (uint32_t id : level.original_ids) kept[id] = 1;
  std::vector<Vec3> removed;
  for (uint32_t i : original.samples) {
    if (!kept[i]) removed.push_back(original.positions[i]);
  }
  const TriangleGrid level_triangles(level.mesh.positions, level.mesh.indices);
  float worst2 = max_nearest2(level_triangles, removed, floor * floor);
  worst2 = max_nearest2(level_triangles, original.surface, worst2);
  worst2 = max_nearest2(original.triangles, level_samples(level.mesh, original.spacing), worst2);
  return std::sqrt(worst2);
}

// The level made of `indices` (into source's vertices): cache-ordered triangles, vertices
// reordered by first use and compacted, attributes and original ids carried along.
BuiltLevel optimised_level(const Mesh& source, const std::vector<uint32_t>& source_ids,
                           std::vector<uint32_t> indices) {
  const size_t vertex_count = source.vertex_count();
  meshopt_optimizeVertexCache(indices.data(), indices.data(), indices.size(), vertex_count);
  std::vector<uint32_t> remap(vertex_count);
  const size_t unique =
      meshopt_optimizeVertexFetchRemap(remap.data(), indices.data(), indices.size(), vertex_count);
  BuiltLevel level;
  level.mesh.indices.resize(indices.size());
  meshopt_remapIndexBuffer(level.mesh.indices.data(), indices.data(), indices.size(), remap.data());
  auto remap_stream = [&](const auto& src, auto& dst) {
    if (src.empty()) return;
    dst.resize(unique);
    meshopt_remapVertexBuffer(dst.data(), src.data(), vertex_count, sizeof(src[0]), remap.data());
  };
  remap_stream(source.positions, level.mesh.positions);
  remap_stream(source.normals, level.mesh.normals);
  remap_stream(source.colors, level.mesh.colors);
  remap_stream(source.uvs, level.mesh.uvs);
  level.mesh.texture = source.texture;
  remap_stream(source_ids, level.original_ids);
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
  BuiltLevel built = optimised_level(mesh, {}, mesh.indices);
  chain.levels.push_back({std::move(built.mesh), mesh.triangle_count(), 0.0f, LodMethod::kOriginal});
  if (chain.levels[0].triangle_count <= params.min_triangles) return chain;

  const Original original = original_of(chain.levels[0].mesh, params.error_samples);
  built.original_ids.resize(original.positions.size());
  std::iota(built.original_ids.begin(), built.original_ids.end(), 0u);
  while (chain.levels.back().triangle_count > params.min_triangles) {
    const LodLevel& previous = chain.levels.back();
    const size_t target = std::max<size_t>(
        params.min_triangles, size_t(std::ceil(previous.triangle_count * params.ratio)));
    Simplified s = simplify_to(previous.mesh, target, params);
    const size_t triangles = s.indices.size() / 3;
    if (triangles == 0 || triangles >= previous.triangle_count) break;  // no progress
    built = optimised_level(previous.mesh, built.original_ids, std::move(s.indices));
    // Measured against the original, not the previous level: errors do not accumulate.
    const float error = measured_error(original, built, std::max(s.error, previous.error));
    chain.levels.push_back({std::move(built.mesh), triangles, error, s.method});
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
