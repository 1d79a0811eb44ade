// Seed 004 (Zheng), §4.5 and Fig. 4.10: the client's selective mesh and its op applier
// (digest §3.7).
#include "cellwalk/systems/vdr/selective_mesh.hpp"

#include <xxhash.h>

#include <algorithm>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/vdr/progressive_mesh.hpp"

namespace cellwalk::vdr {
namespace {

[[noreturn]] void refuse(const char* op, uint32_t node, const std::string& what) {
  fail(std::string(op) + " " + std::to_string(node), what + ": the client is out of step with its server");
}

}  // namespace

SelectiveMesh::SelectiveMesh(std::span<const Vec3> positions, std::span<const Vec3> normals,
                             std::span<const uint32_t> indices)
    : base_vertices_(static_cast<uint32_t>(positions.size())),
      base_triangles_(static_cast<uint32_t>(indices.size() / 3)),
      positions_(positions.begin(), positions.end()),
      normals_(normals.begin(), normals.end()) {
  if (normals.size() != positions.size() || indices.size() % 3 != 0)
    fail("base mesh", "needs one normal per position and three indices per triangle");
  for (uint32_t v = 0; v < base_vertices_; ++v) {
    vertex_slot_.emplace(v, v);
    vertex_id_.push_back(v);
  }
  uses_.assign(base_vertices_, 0);
  for (uint32_t t = 0; t < base_triangles_; ++t) {
    for (int k = 0; k < 3; ++k)
      if (indices[3 * t + k] >= base_vertices_) fail("base mesh", "triangle " + std::to_string(t) + " uses a vertex it lacks");
    add_triangle(t, indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]);
  }
}

uint32_t SelectiveMesh::vertex_slot(uint32_t v, uint32_t node, const char* what) const {
  const auto it = vertex_slot_.find(v);
  if (it == vertex_slot_.end()) refuse(what, node, "vertex " + std::to_string(v) + " is not in the mesh");
  return it->second;
}

uint32_t SelectiveMesh::triangle_slot(uint32_t t) const {
  const auto it = triangle_slot_.find(t);
  return it == triangle_slot_.end() ? kNone : it->second;
}

void SelectiveMesh::add_triangle(uint32_t t, uint32_t a, uint32_t b, uint32_t c) {
  triangle_slot_.emplace(t, static_cast<uint32_t>(triangle_id_.size()));
  triangle_id_.push_back(t);
  for (uint32_t s : {a, b, c}) {
    indices_.push_back(s);
    ++uses_[s];
  }
}

// Swap-remove: the last triangle moves into the hole and its T_F->A entry follows it.
void SelectiveMesh::remove_triangle(uint32_t t) {
  const uint32_t slot = triangle_slot_.at(t), last = static_cast<uint32_t>(triangle_id_.size() - 1);
  for (int k = 0; k < 3; ++k) --uses_[indices_[3 * slot + k]];
  if (slot != last) {
    std::copy_n(indices_.begin() + 3 * last, 3, indices_.begin() + 3 * slot);
    triangle_id_[slot] = triangle_id_[last];
    triangle_slot_[triangle_id_[slot]] = slot;
  }
  indices_.resize(3 * last);
  triangle_id_.pop_back();
  triangle_slot_.erase(t);
}

std::vector<uint32_t> SelectiveMesh::corners_holding(const VsplitOp& op, uint32_t from, const char* what) const {
  std::vector<uint32_t> corners;
  corners.reserve(op.adjusted.size());
  for (uint32_t t : op.adjusted) {
    const uint32_t slot = triangle_slot(t);
    if (slot == kNone) refuse(what, op.node, "adjusted triangle " + std::to_string(t) + " is not in the mesh");
    const auto first = indices_.begin() + 3 * slot;
    const auto it = std::find(first, first + 3, from);
    if (it == first + 3) refuse(what, op.node, "adjusted triangle " + std::to_string(t) + " lacks the corner it changes");
    const auto corner = static_cast<uint32_t>(it - indices_.begin());
    if (std::find(corners.begin(), corners.end(), corner) != corners.end())
      refuse(what, op.node, "adjusted triangle " + std::to_string(t) + " is listed twice");
    corners.push_back(corner);
  }
  return corners;
}

void SelectiveMesh::move_corners(const std::vector<uint32_t>& corners, uint32_t from, uint32_t to) {
  for (uint32_t corner : corners) indices_[corner] = to;
  uses_[from] -= static_cast<uint32_t>(corners.size());
  uses_[to] += static_cast<uint32_t>(corners.size());
}

void SelectiveMesh::vsplit(const VsplitOp& op) {
  const uint32_t c = base_vertices_ + op.node, fl = base_triangles_ + 2 * op.node, fr = fl + 1;
  if (op.node >= kNone / 2 - base_triangles_) refuse("vsplit", op.node, "the node id is out of range");
  if (vertex_slot_.count(c) || triangle_slot(fl) != kNone || triangle_slot(fr) != kNone)
    refuse("vsplit", op.node, "it is already split");
  const uint32_t p = vertex_slot(op.v_p, op.node, "vsplit");
  const uint32_t l = op.v_l == kNone ? kNone : vertex_slot(op.v_l, op.node, "vsplit");
  const uint32_t r = op.v_r == kNone ? kNone : vertex_slot(op.v_r, op.node, "vsplit");
  if (l == kNone && r == kNone) refuse("vsplit", op.node, "it has neither pivot");
  const std::vector<uint32_t> corners = corners_holding(op, p, "vsplit");
  uint32_t slot;
  if (!recycle_.empty()) {
    slot = recycle_.back();
    recycle_.pop_back();
    positions_[slot] = op.position, normals_[slot] = op.normal;
  } else {
    slot = static_cast<uint32_t>(positions_.size());
    positions_.push_back(op.position), normals_.push_back(op.normal), vertex_id_.push_back(kNone), uses_.push_back(0);
  }
  move_corners(corners, p, slot);
  vertex_id_[slot] = c;
  vertex_slot_.emplace(c, slot);
  if (l != kNone) add_triangle(fl, p, slot, l);  // f_l = (v_p, v_c, v_l)
  if (r != kNone) add_triangle(fr, slot, p, r);  // f_r = (v_c, v_p, v_r)
}

void SelectiveMesh::ecol(const VsplitOp& op) {
  const uint32_t c = base_vertices_ + op.node, fl = base_triangles_ + 2 * op.node, fr = fl + 1;
  if (op.node >= kNone / 2 - base_triangles_) refuse("ecol", op.node, "the node id is out of range");
  const uint32_t cs = vertex_slot(c, op.node, "ecol"), p = vertex_slot(op.v_p, op.node, "ecol");
  const uint32_t faces = (triangle_slot(fl) != kNone) + (triangle_slot(fr) != kNone);
  // v_c must be used by f_l, f_r and the adjusted triangles only, or deleting it leaves a hole.
  if (faces == 0 || uses_[cs] != faces + op.adjusted.size())
    refuse("ecol", op.node, "v_c is used by other triangles than f_l, f_r and the adjusted ones");
  move_corners(corners_holding(op, cs, "ecol"), cs, p);
  if (triangle_slot(fl) != kNone) remove_triangle(fl);
  if (triangle_slot(fr) != kNone) remove_triangle(fr);
  vertex_slot_.erase(c);
  vertex_id_[cs] = kNone;
  recycle_.push_back(cs);
}

std::vector<std::array<uint32_t, 3>> SelectiveMesh::triangles_by_id() const {
  std::vector<std::array<uint32_t, 3>> out(triangle_id_.size());
  for (size_t s = 0; s < triangle_id_.size(); ++s)
    for (int k = 0; k < 3; ++k) out[s][k] = vertex_id_[indices_[3 * s + k]];
  return out;
}

uint64_t SelectiveMesh::render_bytes() const {
  return (positions_.size() + normals_.size()) * sizeof(Vec3) + indices_.size() * sizeof(uint32_t);
}

uint64_t SelectiveMesh::aux_bytes() const {
  // An unordered_map node holds the pair, a next pointer and the cached hash; each bucket a pointer.
  const auto map_bytes = [](const std::unordered_map<uint32_t, uint32_t>& m) {
    return m.size() * (sizeof(std::pair<uint32_t, uint32_t>) + 2 * sizeof(void*)) + m.bucket_count() * sizeof(void*);
  };
  return map_bytes(vertex_slot_) + map_bytes(triangle_slot_) +
         (triangle_id_.size() + vertex_id_.size() + recycle_.size() + uses_.size()) * sizeof(uint32_t);
}

uint64_t mesh_digest(const SelectiveMesh& mesh) {
  XXH3_state_t* state = XXH3_createState();
  XXH3_64bits_reset(state);
  XXH3_64bits_update(state, mesh.indices().data(), mesh.indices().size() * sizeof(uint32_t));
  XXH3_64bits_update(state, mesh.positions().data(), mesh.positions().size() * sizeof(Vec3));
  XXH3_64bits_update(state, mesh.normals().data(), mesh.normals().size() * sizeof(Vec3));
  const uint64_t digest = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  return digest;
}

}  // namespace cellwalk::vdr
