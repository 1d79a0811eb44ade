// Discrete level-of-detail chains: each object is stored as a list of ever coarser meshes,
// each with its triangle count and object-space error, so a strategy can pick the coarsest
// level whose projected error stays under a pixel bound.
// Seeds: 000 HDoV thesis §5.6 (digest §3.10, LOD generation); 001 vLOD §2.2 (digest §3.2,
// LODs chosen per view cell). Simplifier: meshoptimizer (QEM edge collapse, Garland and
// Heckbert 1997) with its sloppy grid simplifier as the fallback.
#pragma once

#include <cstddef>
#include <vector>

#include "cellwalk/scene/mesh.hpp"

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
  //  - the distance from each sampled original vertex (see error_samples) and each point of
  //    a grid on the original's triangles (spacing 1/64 of its diagonal; a triangle's
  //    centroid when it is smaller; at most error_samples points) to the nearest triangle of
  //    this level,
  //  - the distance from each vertex and grid point of this level's triangles to the nearest
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

// ---- Internal LODs of tree nodes (HDoV thesis §5.6, digest §3.10) ----------------------------

// How an aggregate is simplified into internal LODs.
enum class AggregateSimplifier {
  // meshopt_simplifySloppy (vertex clustering) step by step: fast, for wide nodes (the disk
  // HDoV-tree's M = 16) whose aggregates are large.
  kClustering,
  // build_lod_chain (QEM edge collapse, clustering on a stall), levels below its level 0: for
  // binary nodes (the k-d scene tree), whose aggregates near the root are so small (tens of
  // triangles) that clustering collapses them to nothing and the node would get no LOD.
  kLodChain,
};

// How a tree node's internal LODs are made from its parts (its children's coarsest levels).
struct AggregateLodParams {
  float ratio = 0.5f;          // each level aims at this fraction of the previous one's triangles
  uint32_t levels = 3;         // at most this many levels are kept
  size_t min_triangles = 8;    // no level is made once the last one has at most this many
  AggregateSimplifier simplifier = AggregateSimplifier::kClustering;
};

// The internal LODs of one node: the parts appended into one aggregate (each part's colour
// written per vertex when it has none, so the aggregate keeps the objects' colours), then
// simplified step by step by params.simplifier. The aggregate itself is
// not kept: levels[0], the finest, has strictly fewer triangles than Σ parts, as §5.6
// requires of a parent's finest LOD against its children's coarsest; each next level has
// strictly fewer than the one before. Empty when not even one step makes progress.
// Used by both trees (the disk HDoV-tree and the k-d scene tree). REQUIRES 0 < ratio < 1.
struct LodPart {
  const Mesh* mesh = nullptr;
  Rgba8 color = 0;
};
std::vector<Mesh> build_aggregate_lods(const std::vector<LodPart>& parts, const AggregateLodParams& params = {});

// The parts appended into one mesh exactly as build_aggregate_lods aggregates them: what a node
// without internal LODs (build_aggregate_lods gave none) hands its parent as its coarsest.
Mesh aggregate_lod_parts(const std::vector<LodPart>& parts);

}  // namespace cellwalk
