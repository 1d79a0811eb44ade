// Discrete level-of-detail chains: each object is stored as a list of ever coarser meshes,
// each with its triangle count and object-space error, so a strategy can pick the coarsest
// level whose projected error stays under a pixel bound.
// Seeds: 000 HDoV thesis §5.6 (digest §3.10, LOD generation); 001 vLOD §2.2 (digest §3.2,
// LODs chosen per view cell). Simplifier: meshoptimizer (QEM edge collapse, Garland and
// Heckbert 1997) with its sloppy grid simplifier as the fallback.
#pragma once

#include <cstddef>
#include <vector>

#include "cellwalk/mesh.hpp"

namespace cellwalk {

struct LodParams {
  // Each level aims at this fraction of the previous level's triangles.
  float ratio = 0.5f;
  // No level is made once the last one has at most this many triangles.
  size_t min_triangles = 32;
  // meshopt_simplify "stalls" when it keeps more than this fraction of the previous level
  // (topology constraints); the level is then made with meshopt_simplifySloppy.
  float stall_fraction = 0.9f;
  // Original vertices sampled (evenly by index) to measure a sloppy level's error.
  size_t error_samples = 4096;
};

enum class LodMethod {
  kOriginal,  // level 0: the input mesh, reordered
  kSimplify,  // meshopt_simplify (topology preserving edge collapse)
  kSloppy,    // meshopt_simplifySloppy (vertex clustering), after a stall
};

struct LodLevel {
  Mesh mesh;
  size_t triangle_count = 0;
  // Object-space error in the mesh's units: how far the level's surface may lie from the
  // original's. kSimplify: meshopt's result_error × meshopt_simplifyScale (a quadric
  // distance to the original triangles' planes). kSloppy: the larger of meshopt's estimate
  // and the measured distance from sampled original vertices to the level's triangles.
  // Never smaller than the previous level's (made non-decreasing along the chain).
  float error = 0.0f;
  LodMethod method = LodMethod::kOriginal;
};

// levels[0] is the finest (error 0), each next level has strictly fewer triangles.
struct LodChain {
  std::vector<LodLevel> levels;
};

// Builds the chain. Every level is simplified from the original mesh (so errors are against
// the original, not accumulated), then vertex-cache optimised and vertex-fetch optimised
// (vertices reordered and compacted; normals and colours follow their positions).
// Stops at params.min_triangles or when neither simplifier makes progress.
// REQUIRES: validate(mesh) passes; 0 < ratio < 1.
LodChain build_lod_chain(const Mesh& mesh, const LodParams& params = {});

// Index of the coarsest level whose projected error error · pixels_per_unit is at most
// pixel_bound; 0 when none is (or pixels_per_unit is infinite). pixels_per_unit comes from
// screen_error.hpp: pixels_per_unit() for a viewpoint, cell_pixels_per_unit() for a cell.
size_t select_level(const LodChain& chain, float pixels_per_unit, float pixel_bound);

}  // namespace cellwalk
