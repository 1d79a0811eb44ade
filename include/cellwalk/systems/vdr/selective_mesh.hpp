// Zheng's client-side selective mesh (seed 004, §4.5, Fig. 4.10; digest §3.7): the arrays a
// renderer draws (positions, normals, indexed triangles) and the id maps that let a client with
// no adjacency and no hierarchy apply a stream of vsplits and ecols:
//   V_F->A, T_F->A   full-model id -> array slot (hashed: sized by the selective mesh, not the
//                    model, as Table 4.2's constant ~0.95 MB of aux memory implies)
//   T_A->F           array slot -> full-model id, so a swap-remove can fix the moved triangle
//   V_recycle        vertex slots an ecol freed, reused by the next vsplits ("pairs").
// A triangle delete is a swap-remove (the index array stays contiguous); a vertex delete leaves
// its slot in place and recycles it.
//
// Thread-safety: none; the client's render thread owns it (§5.4.1).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "cellwalk/core/geometry.hpp"
#include "cellwalk/scene/mesh.hpp"

namespace cellwalk::vdr {

// What a batch carries for one op (docs/protocol.md, "VDR streaming"). An ecol carries v_p and the
// adjusted triangles too: the client keeps no hierarchy to look them up (digest §3.7).
struct VsplitOp {
  uint32_t node = 0;  // vsplit id i: v_c, f_l and f_r follow from it
  uint32_t v_p = 0, v_l = 0, v_r = 0;  // pivots kNone on a boundary
  Vec3 position{0.0f}, normal{0.0f};   // v_c's (unused by an ecol)
  std::span<const uint32_t> adjusted;
};

class SelectiveMesh {
 public:
  // The base mesh M_0: vertices 0..base_vertices-1 and triangles 0..base_triangles-1.
  SelectiveMesh(std::span<const Vec3> positions, std::span<const Vec3> normals, std::span<const uint32_t> indices);

  // Apply one op. Throws Error (naming the node) if the op is not legal on this mesh — v_p, a
  // pivot or an adjusted triangle absent, or an adjusted triangle not holding the corner it
  // changes — and then leaves the mesh as it was: a client out of step with its server must say
  // so, never draw garbage.
  void vsplit(const VsplitOp& op);
  void ecol(const VsplitOp& op);

  // The arrays to draw: indices() refer to positions()/normals() slots; recycled slots hold
  // stale vertices no triangle uses.
  const std::vector<Vec3>& positions() const { return positions_; }
  const std::vector<Vec3>& normals() const { return normals_; }
  const std::vector<uint32_t>& indices() const { return indices_; }
  uint32_t triangle_count() const { return static_cast<uint32_t>(indices_.size() / 3); }
  uint32_t vertex_count() const { return static_cast<uint32_t>(vertex_slot_.size()); }
  // The triangles by full-model vertex ids, one per slot's triangle: what tests compare.
  std::vector<std::array<uint32_t, 3>> triangles_by_id() const;
  // Bytes of the render arrays and of the maps (Table 4.2's "render" and "aux").
  uint64_t render_bytes() const;
  uint64_t aux_bytes() const;

 private:
  uint32_t vertex_slot(uint32_t v, uint32_t node, const char* what) const;
  uint32_t triangle_slot(uint32_t t) const;  // kNone if absent
  void add_triangle(uint32_t t, uint32_t a, uint32_t b, uint32_t c);
  void remove_triangle(uint32_t t);
  // The index-array positions of corner `from` (a slot) in each adjusted triangle; throws when
  // one is absent, lacks it or is listed twice, before anything has changed.
  std::vector<uint32_t> corners_holding(const VsplitOp& op, uint32_t from, const char* what) const;
  void move_corners(const std::vector<uint32_t>& corners, uint32_t from, uint32_t to);

  uint32_t base_vertices_, base_triangles_;
  std::vector<Vec3> positions_, normals_;
  std::vector<uint32_t> indices_;
  std::unordered_map<uint32_t, uint32_t> vertex_slot_, triangle_slot_;  // V_F->A, T_F->A
  std::vector<uint32_t> triangle_id_;                                   // T_A->F
  std::vector<uint32_t> vertex_id_;                                     // slot -> id (kNone free)
  std::vector<uint32_t> recycle_;                                       // V_recycle
  std::vector<uint32_t> uses_;  // per vertex slot, the triangle corners on it
};

// The lockstep digest (docs/protocol.md): XXH3 of the index, position and normal arrays as they
// lie. Two meshes that took the same ops from the same base have the same arrays, slot for slot.
uint64_t mesh_digest(const SelectiveMesh& mesh);

// The op a batch or the model describes, as SelectiveMesh takes it. `adjusted` is viewed, not copied.
template <typename OpLike>
VsplitOp vsplit_op(const OpLike& op) {
  return VsplitOp{op.node, op.v_p, op.v_l, op.v_r, op.position, op.normal, op.adjusted};
}

}  // namespace cellwalk::vdr
