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
  // Original vertices whose distance to every level is measured: all of them when the mesh
  // has at most this many (the measurement is then exact for vertices), else this many
  // evenly spaced by index.
  size_t error_samples = 100000;
};

enum class LodMethod {
  kOriginal,  // level 0: the input mesh, reordered
  kSimplify,  // meshopt_simplify (topology preserving edge collapse)
  kSloppy,    // meshopt_simplifySloppy (vertex clustering), after a stall
};

struct LodLevel {
  Mesh mesh;
  size_t triangle_count = 0;
  // Object-space error in the mesh's units: how far the level's surface lies from the
  // original's, measured both ways against the ORIGINAL mesh. The largest of
  //  - the distance from each sampled original vertex (see error_samples) to the nearest
  //    triangle of this level,
  //  - the distance from each vertex and triangle centroid of this level to the nearest
  //    original triangle,
  //  - meshopt's own estimate for the step from the previous level, and the previous
  //    level's error (so errors never decrease along the chain).
  // Distances are exact point–triangle distances. Points between the samples are not
  // measured: this is not the Hausdorff distance between the surfaces (docs/lod.md).
  float error = 0.0f;
  LodMethod method = LodMethod::kOriginal;
};

// levels[0] is the finest (error 0), each next level has strictly fewer triangles.
struct LodChain {
  std::vector<LodLevel> levels;
};

// Builds the chain. Every level is simplified from the previous one (so the whole chain costs
// about two simplifications of the input), its error measured against the original, then
// vertex-cache optimised and vertex-fetch optimised (vertices reordered and compacted;
// normals and colours follow their positions).
// Stops at params.min_triangles or when neither simplifier makes progress.
// REQUIRES: validate(mesh) passes; 0 < ratio < 1.
LodChain build_lod_chain(const Mesh& mesh, const LodParams& params = {});

// Index of the coarsest level whose projected error error · pixels_per_unit is at most
// pixel_bound; 0 when none is (or pixels_per_unit is infinite). pixels_per_unit comes from
// screen_error.hpp: pixels_per_unit() for a viewpoint, cell_pixels_per_unit() for a cell.
size_t select_level(const LodChain& chain, float pixels_per_unit, float pixel_bound);

}  // namespace cellwalk
