// Zheng's progressive mesh (seed 004, §3.2; digest §2 steps 2–3, §3.1): a quadric-error
// half-edge-collapse simplification, recorded collapse by collapse and reversed into a base mesh
// M_0 and vertex splits vsplit_0 .. vsplit_{n-1}, with implicit ids.
//
// Implicit ids (§3.2): base vertices are 0 .. base_vertex_count-1 and base triangles
// 0 .. base_triangle_count-1; vsplit i creates vertex v_c = base_vertex_count + i and the
// triangle slots f_l = base_triangle_count + 2i and f_r = f_l + 1. A vsplit adds
// f_l = (v_p, v_c, v_l) and f_r = (v_c, v_p, v_r) (a boundary split lacks one: its pivot is kNone
// and its slot stays empty) and, in each adjusted triangle, replaces the corner v_p by v_c.
// The ecol is the exact reverse. PM order is a topological order: everything a vsplit needs was
// created by a vsplit with a smaller id (or is in the base).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "cellwalk/scene/mesh.hpp"

namespace cellwalk::vdr {

constexpr uint32_t kNone = 0xFFFFFFFFu;

struct ProgressiveMesh {
  uint32_t base_vertex_count = 0;
  uint32_t base_triangle_count = 0;
  std::vector<Vec3> positions;          // every vertex: the base's, then v_c of each vsplit
  std::vector<Vec3> normals;            // one per position (the input's, or area-weighted)
  std::vector<uint32_t> base_indices;   // three per base triangle, counter-clockwise
  // vsplit i, structure of arrays:
  std::vector<uint32_t> v_p, v_l, v_r;  // v_l / v_r are kNone on a boundary
  std::vector<float> error;             // the collapse's quadric error QE (squared distances)
  std::vector<uint32_t> adjusted_offsets{0};  // CSR: adjusted[offsets[i] .. offsets[i+1])
  std::vector<uint32_t> adjusted;       // triangle ids whose v_p corner becomes v_c

  uint32_t vsplit_count() const { return static_cast<uint32_t>(v_p.size()); }
  uint32_t vertex_count() const { return static_cast<uint32_t>(positions.size()); }
  uint32_t triangle_slots() const { return base_triangle_count + 2 * vsplit_count(); }
  uint32_t v_c(uint32_t i) const { return base_vertex_count + i; }
  uint32_t f_l(uint32_t i) const { return base_triangle_count + 2 * i; }
  uint32_t f_r(uint32_t i) const { return base_triangle_count + 2 * i + 1; }
  std::span<const uint32_t> adjusted_of(uint32_t i) const {
    return {adjusted.data() + adjusted_offsets[i], adjusted.data() + adjusted_offsets[i + 1]};
  }
  // The vsplit that created vertex v / triangle t, or kNone for the base's.
  uint32_t vertex_creator(uint32_t v) const { return v < base_vertex_count ? kNone : v - base_vertex_count; }
  uint32_t triangle_creator(uint32_t t) const {
    return t < base_triangle_count ? kNone : (t - base_triangle_count) / 2;
  }
};

struct PmBuildOptions {
  // Stop collapsing at this many triangles (the thesis leaves M_0's size open; its Dragon starts
  // under 3k). Collapsing also stops when no legal collapse is left.
  uint32_t base_triangles = 1000;
  // No collapse may leave v_p with more neighbours: keeps every vsplit's adjusted list, and so
  // every op on the wire, bounded.
  uint32_t max_valence = 24;
  // Weight of the planes through boundary edges, perpendicular to their face (Garland and
  // Heckbert's boundary constraint): keeps holes and open borders in place.
  double boundary_weight = 4.0;
};

// Progress: (collapses done, collapses the target allows at most).
using PmProgress = std::function<void(uint64_t, uint64_t)>;

// Simplifies `mesh` by half-edge collapses v_c -> v_p in order of least quadric error (Garland
// and Heckbert's quadrics of the faces' planes, summed, unweighted, evaluated at v_p, which does
// not move). Vertices with equal positions are welded first; degenerate and duplicate triangles
// are dropped. A collapse is taken only if it is manifold (the link condition: the neighbours v_c
// and v_p share are exactly v_l and v_r), keeps borders (a border v_c only along a border edge),
// turns no adjusted face's normal by more than 90°, makes no duplicate face and respects
// max_valence; vertices around non-manifold edges or fans never move.
// Throws Error naming `where` when the mesh has no triangle.
ProgressiveMesh build_progressive_mesh(const Mesh& mesh, const PmBuildOptions& options, std::string_view where,
                                       const PmProgress& progress = {});

// The mesh with exactly the vsplits in `split` applied (split.size() == vsplit_count()),
// applied in increasing id order: the oracle every partial refinement is checked against.
// REQUIRES: `split` is closed under potential_parents (below).
// Indices refer to `positions`; unused vertices stay in the array.
Mesh mesh_with_splits(const ProgressiveMesh& pm, const std::vector<bool>& split);

// Every vsplit's dependency list (§3.2): the creators of v_p, v_l, v_r and the adjusted
// triangles, without the base's, sorted by decreasing id, each once: the potential parents.
void potential_parents(const ProgressiveMesh& pm, uint32_t i, std::vector<uint32_t>& out);

}  // namespace cellwalk::vdr
