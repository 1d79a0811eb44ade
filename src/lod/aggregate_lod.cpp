// HDoV thesis §5.6 (digest §3.10): internal LODs of tree nodes, aggregates of the children's
// coarsest levels simplified bottom-up, the parent's finest LOD smaller than Σ children's coarsest.
#include <algorithm>

#include <meshoptimizer.h>

#include "cellwalk/lod/lod.hpp"

namespace cellwalk {

Mesh aggregate_lod_parts(const std::vector<LodPart>& parts) {
  Mesh all;
  for (const LodPart& part : parts) {
    Mesh coloured = *part.mesh;
    if (coloured.colors.empty()) coloured.colors.assign(coloured.positions.size(), part.color);
    if (coloured.normals.empty() && !all.normals.empty()) compute_normals(coloured);
    append(all, coloured);
  }
  return all;
}

namespace {

// `mesh` with `indices`, keeping only the vertices they use.
Mesh compact(const Mesh& mesh, const std::vector<uint32_t>& indices) {
  std::vector<uint32_t> remap(mesh.positions.size(), UINT32_MAX);
  Mesh out;
  out.texture = mesh.texture;
  out.indices.reserve(indices.size());
  for (uint32_t v : indices) {
    if (remap[v] == UINT32_MAX) {
      remap[v] = static_cast<uint32_t>(out.positions.size());
      out.positions.push_back(mesh.positions[v]);
      if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[v]);
      if (!mesh.colors.empty()) out.colors.push_back(mesh.colors[v]);
      if (!mesh.uvs.empty()) out.uvs.push_back(mesh.uvs[v]);
    }
    out.indices.push_back(remap[v]);
  }
  return out;
}

// Vertex clustering from each level to the next (the parts are disjoint, so topology-preserving
// collapse would stall on wide nodes' large aggregates).
std::vector<Mesh> clustered_levels(const Mesh& all, const AggregateLodParams& params) {
  std::vector<Mesh> levels;
  const Mesh* previous = &all;
  while (levels.size() < params.levels && previous->triangle_count() > params.min_triangles) {
    const size_t before = previous->triangle_count();
    const size_t target = std::max<size_t>(1, static_cast<size_t>(double(before) * params.ratio)) * 3;
    std::vector<uint32_t> indices(previous->indices.size());
    indices.resize(meshopt_simplifySloppy(indices.data(), previous->indices.data(), previous->indices.size(),
                                          &previous->positions[0].x, previous->positions.size(), sizeof(Vec3),
                                          target, 1.0f));
    if (indices.empty() || indices.size() / 3 >= before) break;  // no progress: stop the chain
    levels.push_back(compact(*previous, indices));
    previous = &levels.back();
  }
  return levels;
}

// The levels of build_lod_chain below its level 0 (the aggregate itself, reordered).
std::vector<Mesh> chain_levels(const Mesh& all, const AggregateLodParams& params) {
  LodChain chain = build_lod_chain(all, {.ratio = params.ratio, .min_triangles = params.min_triangles});
  std::vector<Mesh> levels;
  for (size_t l = 1; l < chain.levels.size() && levels.size() < params.levels; ++l)
    levels.push_back(std::move(chain.levels[l].mesh));
  return levels;
}

}  // namespace

std::vector<Mesh> build_aggregate_lods(const std::vector<LodPart>& parts, const AggregateLodParams& params) {
  const Mesh all = aggregate_lod_parts(parts);
  return params.simplifier == AggregateSimplifier::kLodChain ? chain_levels(all, params) : clustered_levels(all, params);
}

}  // namespace cellwalk
