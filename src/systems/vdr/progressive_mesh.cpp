// Seed 004 (Zheng), §3.2: the quadric-error half-edge-collapse progressive mesh, its legality
// checks and the implicit-id renumbering (digest §2 steps 2–3, §3.1).
// Michael Garland and Paul S. Heckbert. Surface simplification using quadric error metrics. 1997.
#include "cellwalk/systems/vdr/progressive_mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <queue>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "cellwalk/core/error.hpp"

namespace cellwalk::vdr {
namespace {

using DVec3 = glm::dvec3;

// A symmetric 4×4 quadric, upper triangle: a plane n·x + d = 0 adds (n, d)(n, d)^T.
struct Quadric {
  std::array<double, 10> q{};
  void add_plane(const DVec3& n, double d, double w) {
    const double v[4] = {n.x, n.y, n.z, d};
    int k = 0;
    for (int r = 0; r < 4; ++r)
      for (int c = r; c < 4; ++c) q[k++] += w * v[r] * v[c];
  }
  void add(const Quadric& o) {
    for (int k = 0; k < 10; ++k) q[k] += o.q[k];
  }
  double at(const DVec3& p) const {
    const double v[4] = {p.x, p.y, p.z, 1.0};
    double sum = 0;
    int k = 0;
    for (int r = 0; r < 4; ++r)
      for (int c = r; c < 4; ++c) sum += (r == c ? 1.0 : 2.0) * q[k++] * v[r] * v[c];
    return std::max(sum, 0.0);
  }
};

using Face = std::array<uint32_t, 3>;

// The input welded by position, without degenerate or repeated triangles and unused vertices.
struct CleanMesh {
  std::vector<Vec3> positions, normals;
  std::vector<Face> faces;
};

struct PositionHash {
  size_t operator()(const Vec3& p) const {
    uint32_t b[3];
    std::memcpy(b, &p, sizeof b);
    return (size_t(b[0]) * 0x9E3779B1u) ^ (size_t(b[1]) * 0x85EBCA77u) ^ (size_t(b[2]) * 0xC2B2AE3Du);
  }
};

struct FaceHash {
  size_t operator()(const Face& f) const {
    return size_t(f[0]) * 0x9E3779B97F4A7C15ull ^ size_t(f[1]) * 0xC2B2AE3D27D4EB4Full ^ f[2];
  }
};

CleanMesh clean(const Mesh& mesh, std::string_view where) {
  std::unordered_map<Vec3, uint32_t, PositionHash> first;
  std::vector<uint32_t> weld(mesh.positions.size());
  CleanMesh out;
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    // +0.0 and -0.0 weld: they are one point.
    const Vec3 p = mesh.positions[v] + Vec3(0.0f);
    weld[v] = first.try_emplace(p, static_cast<uint32_t>(first.size())).first->second;
  }
  std::vector<uint32_t> used(first.size(), kNone);
  std::unordered_set<Face, FaceHash> seen;  // sorted corners of the faces kept
  std::vector<Face> faces;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    Face f{weld[mesh.indices[t]], weld[mesh.indices[t + 1]], weld[mesh.indices[t + 2]]};
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) continue;
    Face s = f;
    std::sort(s.begin(), s.end());
    if (!seen.insert(s).second) continue;  // the same triangle again (either winding)
    faces.push_back(f);
  }
  if (faces.empty()) fail(where, "has no triangle with three distinct corners: nothing to simplify");
  for (Face& f : faces)
    for (uint32_t& v : f) {
      if (used[v] == kNone) used[v] = static_cast<uint32_t>(out.positions.size()), out.positions.push_back(Vec3(0.0f));
      v = used[v];
    }
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    if (used[weld[v]] != kNone) out.positions[used[weld[v]]] = mesh.positions[v];
  out.faces = std::move(faces);
  // The input's normals are kept where no vertex was welded; otherwise seams had several.
  if (!mesh.normals.empty() && first.size() == mesh.positions.size() && out.positions.size() == mesh.positions.size()) {
    out.normals.resize(out.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v) out.normals[used[weld[v]]] = mesh.normals[v];
  } else {
    Mesh m;
    m.positions = out.positions;
    for (const Face& f : out.faces) m.indices.insert(m.indices.end(), f.begin(), f.end());
    compute_normals(m);
    out.normals = std::move(m.normals);
  }
  return out;
}

struct Collapse {
  uint32_t c, p, l, r;          // v_c, v_p, v_l, v_r (kNone when that face is absent)
  uint32_t face_l, face_r;      // the removed faces (kNone when absent)
  std::vector<uint32_t> adjusted;  // faces whose corner c became p
  float error;
};

struct Candidate {
  double cost;
  uint32_t c, p, stamp;
  bool operator>(const Candidate& o) const { return cost > o.cost; }
};

class Simplifier {
 public:
  Simplifier(CleanMesh mesh, const PmBuildOptions& options) : m_(std::move(mesh)), options_(options) {
    const size_t nv = m_.positions.size();
    vfaces_.resize(nv);
    alive_.assign(nv, 1);
    stamp_.assign(nv, 0);
    locked_.assign(nv, 0);
    border_.assign(nv, 0);
    quadric_.resize(nv);
    face_alive_.assign(m_.faces.size(), 1);
    for (uint32_t f = 0; f < m_.faces.size(); ++f)
      for (uint32_t v : m_.faces[f]) vfaces_[v].push_back(f);
    classify_edges();
    for (uint32_t v = 0; v < nv; ++v) lock_if_not_one_fan(v);
    for (uint32_t f = 0; f < m_.faces.size(); ++f) add_face_planes(f);
  }

  std::vector<Collapse> run(const PmProgress& progress) {
    live_faces_ = m_.faces.size();
    for (uint32_t v = 0; v < m_.positions.size(); ++v) push_best(v);
    const uint64_t most = live_faces_ > options_.base_triangles ? (live_faces_ - options_.base_triangles) / 2 : 0;
    while (live_faces_ > options_.base_triangles && !heap_.empty()) {
      const Candidate top = heap_.top();
      heap_.pop();
      if (!alive_[top.c] || top.stamp != stamp_[top.c]) continue;
      if (!alive_[top.p] || !legal(top.c, top.p)) {  // the 2-ring changed since it was pushed
        push_best(top.c);
        continue;
      }
      collapse(top.c, top.p);
      if (progress && (collapses_.size() & 1023) == 0) progress(collapses_.size(), most);
    }
    return std::move(collapses_);
  }

  const CleanMesh& mesh() const { return m_; }
  const std::vector<uint8_t>& face_alive() const { return face_alive_; }
  const std::vector<uint8_t>& vertex_alive() const { return alive_; }

 private:
  DVec3 pos(uint32_t v) const { return DVec3(m_.positions[v]); }

  // Border edges (one face) mark their ends; an edge with more than two faces, or two faces
  // that run it the same way, locks its ends: no manifold collapse is defined there.
  void classify_edges() {
    std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> edges;  // undirected -> (count, a->b count)
    for (const Face& f : m_.faces)
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = f[k], b = f[(k + 1) % 3];
        auto& e = edges[uint64_t(std::min(a, b)) << 32 | std::max(a, b)];
        ++e.first;
        if (a < b) ++e.second;
      }
    for (const auto& [key, e] : edges) {
      const uint32_t a = uint32_t(key >> 32), b = uint32_t(key);
      if (e.first == 1) border_[a] = border_[b] = 1;
      if (e.first > 2 || (e.first == 2 && e.second != 1)) locked_[a] = locked_[b] = 1;
    }
  }

  // A vertex whose faces form more than one fan (a bow-tie) is non-manifold: it never moves.
  void lock_if_not_one_fan(uint32_t v) {
    const auto& fs = vfaces_[v];
    std::vector<uint32_t> parent(fs.size());
    for (uint32_t i = 0; i < fs.size(); ++i) parent[i] = i;
    const auto find = [&](uint32_t i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    for (uint32_t i = 0; i < fs.size(); ++i)
      for (uint32_t j = i + 1; j < fs.size(); ++j)
        if (shared_other_vertex(fs[i], fs[j], v)) parent[find(i)] = find(j);
    uint32_t fans = 0;
    for (uint32_t i = 0; i < fs.size(); ++i) fans += find(i) == i;
    if (fans > 1) locked_[v] = 1;
  }

  bool shared_other_vertex(uint32_t f, uint32_t g, uint32_t v) const {
    for (uint32_t a : m_.faces[f])
      if (a != v && std::find(m_.faces[g].begin(), m_.faces[g].end(), a) != m_.faces[g].end()) return true;
    return false;
  }

  void add_face_planes(uint32_t f) {
    const Face& t = m_.faces[f];
    const DVec3 a = pos(t[0]), b = pos(t[1]), c = pos(t[2]);
    DVec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    if (len == 0) return;
    n /= len;
    Quadric q;
    q.add_plane(n, -glm::dot(n, a), 1.0);
    for (uint32_t v : t) quadric_[v].add(q);
    // Garland–Heckbert border constraint: a plane through each border edge, perpendicular to f.
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = t[k], w = t[(k + 1) % 3];
      if (!border_[u] || !border_[w] || faces_on_edge(u, w) != 1) continue;
      DVec3 m = glm::cross(pos(w) - pos(u), n);
      const double ml = glm::length(m);
      if (ml == 0) continue;
      m /= ml;
      Quadric e;
      e.add_plane(m, -glm::dot(m, pos(u)), options_.boundary_weight);
      quadric_[u].add(e);
      quadric_[w].add(e);
    }
  }

  uint32_t faces_on_edge(uint32_t u, uint32_t w) const {
    uint32_t n = 0;
    for (uint32_t f : vfaces_[u]) n += std::find(m_.faces[f].begin(), m_.faces[f].end(), w) != m_.faces[f].end();
    return n;
  }

  void ring(uint32_t v, std::vector<uint32_t>& out) const {
    out.clear();
    for (uint32_t f : vfaces_[v])
      for (uint32_t a : m_.faces[f])
        if (a != v) out.push_back(a);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  // §3.1's legality as a simplifier must guarantee it: a manifold collapse c -> p whose every
  // adjusted face keeps its orientation (the seed's 90° fold-over rule).
  bool legal(uint32_t c, uint32_t p) {
    if (locked_[c] || locked_[p] || c == p) return false;
    uint32_t on_edge = 0, opposite[2] = {kNone, kNone};
    for (uint32_t f : vfaces_[c]) {
      const Face& t = m_.faces[f];
      const auto it = std::find(t.begin(), t.end(), p);
      if (it == t.end()) continue;
      if (on_edge == 2) return false;
      opposite[on_edge++] = t[0] ^ t[1] ^ t[2] ^ c ^ p;
    }
    if (on_edge == 0) return false;
    if (border_[c] && on_edge != 1) return false;  // a border vertex leaves only along the border
    ring(c, ring_c_);
    ring(p, ring_p_);
    shared_.clear();
    std::set_intersection(ring_c_.begin(), ring_c_.end(), ring_p_.begin(), ring_p_.end(), std::back_inserter(shared_));
    if (shared_.size() != on_edge) return false;  // the link condition
    for (uint32_t k = 0; k < on_edge; ++k)
      if (!std::binary_search(shared_.begin(), shared_.end(), opposite[k])) return false;
    if (ring_c_.size() + ring_p_.size() - on_edge - 2 > options_.max_valence) return false;
    if (vfaces_[c].size() + vfaces_[p].size() <= 2 * on_edge) return false;  // nothing would remain
    return keeps_orientation(c, p);
  }

  bool keeps_orientation(uint32_t c, uint32_t p) const {
    const DVec3 pc = pos(c), pp = pos(p);
    for (uint32_t f : vfaces_[c]) {
      const Face& t = m_.faces[f];
      if (std::find(t.begin(), t.end(), p) != t.end()) continue;
      const int k = t[0] == c ? 0 : t[1] == c ? 1 : 2;
      const DVec3 a = pos(t[(k + 1) % 3]), b = pos(t[(k + 2) % 3]);
      const DVec3 before = glm::cross(a - pc, b - pc), after = glm::cross(a - pp, b - pp);
      if (glm::dot(before, after) <= 0) return false;
      // The face (p, a, b) must not exist already (a tetrahedron's last collapse).
      for (uint32_t g : vfaces_[p]) {
        const Face& u = m_.faces[g];
        const bool has_a = std::find(u.begin(), u.end(), t[(k + 1) % 3]) != u.end();
        const bool has_b = std::find(u.begin(), u.end(), t[(k + 2) % 3]) != u.end();
        if (has_a && has_b) return false;
      }
    }
    return true;
  }

  double cost(uint32_t c, uint32_t p) const {
    Quadric q = quadric_[c];
    q.add(quadric_[p]);
    return q.at(pos(p));
  }

  // Pushes c's cheapest legal collapse (if any) under a new stamp, which retires older entries.
  void push_best(uint32_t c) {
    ++stamp_[c];
    if (!alive_[c] || locked_[c]) return;
    std::vector<uint32_t> neighbours;
    ring(c, neighbours);
    Candidate best{std::numeric_limits<double>::infinity(), c, kNone, stamp_[c]};
    for (uint32_t p : neighbours) {
      const double e = cost(c, p);
      if (e < best.cost && legal(c, p)) best.cost = e, best.p = p;
    }
    if (best.p != kNone) heap_.push(best);
  }

  void collapse(uint32_t c, uint32_t p) {
    Collapse rec{c, p, kNone, kNone, kNone, kNone, {}, static_cast<float>(cost(c, p))};
    for (uint32_t f : vfaces_[c]) {
      Face& t = m_.faces[f];
      const int k = t[0] == c ? 0 : t[1] == c ? 1 : 2;
      const uint32_t next = t[(k + 1) % 3], prev = t[(k + 2) % 3];
      if (next == p || prev == p) {
        // f_l = (v_p, v_c, v_l): p comes just before c; f_r = (v_c, v_p, v_r): just after.
        if (prev == p) rec.face_l = f, rec.l = next;
        else rec.face_r = f, rec.r = prev;
        face_alive_[f] = 0;
        --live_faces_;
        for (uint32_t a : t)
          if (a != c) std::erase(vfaces_[a], f);
        continue;
      }
      t[k] = p;
      rec.adjusted.push_back(f);
      vfaces_[p].push_back(f);
    }
    vfaces_[c].clear();
    alive_[c] = 0;
    quadric_[p].add(quadric_[c]);
    collapses_.push_back(std::move(rec));
    std::vector<uint32_t> around;
    ring(p, around);
    push_best(p);
    for (uint32_t v : around) push_best(v);
  }

  CleanMesh m_;
  PmBuildOptions options_;
  std::vector<std::vector<uint32_t>> vfaces_;
  std::vector<uint8_t> alive_, locked_, border_, face_alive_;
  std::vector<uint32_t> stamp_;
  std::vector<Quadric> quadric_;
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> heap_;
  std::vector<Collapse> collapses_;
  size_t live_faces_ = 0;
  std::vector<uint32_t> ring_c_, ring_p_, shared_;
};

uint32_t mapped(const std::vector<uint32_t>& ids, uint32_t v) { return v == kNone ? kNone : ids[v]; }

// §3.2: reverses the collapses into vsplits and numbers everything implicitly.
ProgressiveMesh renumber(const Simplifier& s, const std::vector<Collapse>& collapses) {
  const CleanMesh& m = s.mesh();
  const uint32_t n = static_cast<uint32_t>(collapses.size());
  ProgressiveMesh pm;
  std::vector<uint32_t> vid(m.positions.size(), kNone), fid(m.faces.size(), kNone);
  for (uint32_t v = 0; v < m.positions.size(); ++v)
    if (s.vertex_alive()[v]) vid[v] = pm.base_vertex_count++;
  for (uint32_t f = 0; f < m.faces.size(); ++f)
    if (s.face_alive()[f]) fid[f] = pm.base_triangle_count++;
  for (uint32_t k = 0; k < n; ++k) {
    const uint32_t i = n - 1 - k;
    vid[collapses[k].c] = pm.base_vertex_count + i;
    if (collapses[k].face_l != kNone) fid[collapses[k].face_l] = pm.base_triangle_count + 2 * i;
    if (collapses[k].face_r != kNone) fid[collapses[k].face_r] = pm.base_triangle_count + 2 * i + 1;
  }
  pm.positions.resize(m.positions.size());
  pm.normals.resize(m.positions.size());
  for (uint32_t v = 0; v < m.positions.size(); ++v) {
    pm.positions[vid[v]] = m.positions[v];
    pm.normals[vid[v]] = m.normals[v];
  }
  for (uint32_t f = 0; f < m.faces.size(); ++f)
    if (s.face_alive()[f])
      for (uint32_t v : m.faces[f]) pm.base_indices.push_back(vid[v]);
  pm.v_p.resize(n), pm.v_l.resize(n), pm.v_r.resize(n), pm.error.resize(n);
  pm.adjusted_offsets.assign(n + 1, 0);
  for (uint32_t i = 0; i < n; ++i) {
    const Collapse& c = collapses[n - 1 - i];
    pm.v_p[i] = vid[c.p];
    pm.v_l[i] = mapped(vid, c.l);
    pm.v_r[i] = mapped(vid, c.r);
    pm.error[i] = c.error;
    for (uint32_t f : c.adjusted) pm.adjusted.push_back(fid[f]);
    pm.adjusted_offsets[i + 1] = static_cast<uint32_t>(pm.adjusted.size());
  }
  return pm;
}

}  // namespace

ProgressiveMesh build_progressive_mesh(const Mesh& mesh, const PmBuildOptions& options, std::string_view where,
                                       const PmProgress& progress) {
  Simplifier s(clean(mesh, where), options);
  const std::vector<Collapse> collapses = s.run(progress);
  return renumber(s, collapses);
}

Mesh mesh_with_splits(const ProgressiveMesh& pm, const std::vector<bool>& split) {
  std::vector<Face> slots(pm.triangle_slots(), Face{kNone, kNone, kNone});
  for (uint32_t t = 0; t < pm.base_triangle_count; ++t)
    slots[t] = {pm.base_indices[3 * t], pm.base_indices[3 * t + 1], pm.base_indices[3 * t + 2]};
  for (uint32_t i = 0; i < pm.vsplit_count(); ++i) {
    if (!split[i]) continue;
    const uint32_t p = pm.v_p[i], c = pm.v_c(i);
    if (pm.v_l[i] != kNone) slots[pm.f_l(i)] = {p, c, pm.v_l[i]};
    if (pm.v_r[i] != kNone) slots[pm.f_r(i)] = {c, p, pm.v_r[i]};
    for (uint32_t t : pm.adjusted_of(i))
      for (uint32_t& v : slots[t])
        if (v == p) v = c;
  }
  Mesh out;
  out.positions = pm.positions;
  out.normals = pm.normals;
  for (const Face& f : slots)
    if (f[0] != kNone) out.indices.insert(out.indices.end(), f.begin(), f.end());
  return out;
}

void potential_parents(const ProgressiveMesh& pm, uint32_t i, std::vector<uint32_t>& out) {
  out.clear();
  const auto add = [&](uint32_t creator) {
    if (creator != kNone) out.push_back(creator);
  };
  add(pm.vertex_creator(pm.v_p[i]));
  if (pm.v_l[i] != kNone) add(pm.vertex_creator(pm.v_l[i]));
  if (pm.v_r[i] != kNone) add(pm.vertex_creator(pm.v_r[i]));
  for (uint32_t t : pm.adjusted_of(i)) add(pm.triangle_creator(t));
  std::sort(out.begin(), out.end(), std::greater<>());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

}  // namespace cellwalk::vdr
