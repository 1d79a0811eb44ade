// Conservative occluders derived from arbitrary meshes, and the single-occluder test.
// Seeds: 001 vLOD §5.2.2 (convex occluders; concave ones need a conservative stand-in) and
// 000 HDoV thesis §5.5.1 (8-vertex test). The stand-in here: axis-aligned boxes inscribed in
// the mesh's solid, found on a voxel grid classified by crossing parity.
#include "precompute/occluders.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <map>
#include <optional>
#include <unordered_map>

namespace cellwalk::visibility {
namespace {

struct PositionKey {
  uint32_t x, y, z;
  bool operator==(const PositionKey&) const = default;
};
struct PositionHash {
  size_t operator()(const PositionKey& k) const {
    return (uint64_t(k.x) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(k.y) * 0xC2B2AE3D27D4EB4Full) ^
           (uint64_t(k.z) * 0x165667B19E3779F9ull);
  }
};

PositionKey key_of(const Vec3& p) {
  PositionKey k;
  std::memcpy(&k.x, &p.x, 4);
  std::memcpy(&k.y, &p.y, 4);
  std::memcpy(&k.z, &p.z, 4);
  return k;
}

// Ids equal for equal positions: meshes split vertices for normals, the solid is positional.
std::vector<uint32_t> welded_ids(const Mesh& mesh) {
  std::unordered_map<PositionKey, uint32_t, PositionHash> ids;
  ids.reserve(mesh.positions.size());
  std::vector<uint32_t> out(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    out[i] = ids.emplace(key_of(mesh.positions[i]), uint32_t(ids.size())).first->second;
  return out;
}

// The classification grid over the mesh's box: n voxels per axis (anisotropic voxels), and
// per axis a sample offset inside each voxel so that sample rays rarely run exactly along
// the axis-aligned features of generated geometry.
struct Grid {
  std::array<double, 3> origin{}, voxel{};
  int n = 0;
  static constexpr std::array<double, 3> kSampleOffset{0.5 + 0.1371, 0.5 + 0.2719,
                                                       0.5 - 0.3141};

  size_t index(int i, int j, int k) const { return (size_t(k) * n + j) * n + i; }
  size_t size() const { return size_t(n) * n * n; }
  double sample(int axis, int i) const {
    return origin[axis] + (i + kSampleOffset[axis]) * voxel[axis];
  }
  int cell_of(int axis, double x) const {
    return std::clamp(int(std::floor((x - origin[axis]) / voxel[axis])), 0, n - 1);
  }
};

using Cell = std::array<int, 3>;

// Marks voxels a triangle may touch: its box (grown by eps) and its plane both meet them.
void mark_surface(const Grid& g, const Mesh& mesh, std::vector<uint8_t>& surface) {
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    std::array<glm::dvec3, 3> p;
    for (int c = 0; c < 3; ++c) p[c] = glm::dvec3(mesh.positions[mesh.indices[t + c]]);
    const glm::dvec3 normal = glm::cross(p[1] - p[0], p[2] - p[0]);
    Cell lo, hi;
    glm::dvec3 half, eps;
    for (int a = 0; a < 3; ++a) {
      eps[a] = g.voxel[a] * 1e-3;
      half[a] = g.voxel[a] * 0.5 + eps[a];
      lo[a] = g.cell_of(a, std::min({p[0][a], p[1][a], p[2][a]}) - eps[a]);
      hi[a] = g.cell_of(a, std::max({p[0][a], p[1][a], p[2][a]}) + eps[a]);
    }
    const double reach = std::abs(normal.x) * half.x + std::abs(normal.y) * half.y +
                         std::abs(normal.z) * half.z;
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const glm::dvec3 centre(g.origin[0] + (i + 0.5) * g.voxel[0],
                                  g.origin[1] + (j + 0.5) * g.voxel[1],
                                  g.origin[2] + (k + 0.5) * g.voxel[2]);
          if (std::abs(glm::dot(normal, centre - p[0])) <= reach) surface[g.index(i, j, k)] = 1;
        }
  }
}

double edge(double ax, double ay, double bx, double by, double px, double py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

// How the line parallel to `axis` through (sb, sc) on the other two axes meets triangle p:
// missing it (outside, or a zero-area projection), through its interior at `at` along the
// axis (sign: the triangle's orientation seen along the axis), or exactly through an edge or
// vertex, where counting the crossing would be a guess.
struct LineCrossing {
  enum Kind { kMiss, kHit, kDoubtful } kind = kMiss;
  double at = 0.0;
  int sign = 0;
};

LineCrossing line_crossing(const std::array<glm::dvec3, 3>& p, int axis, double sb, double sc) {
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  const double e0 = edge(p[1][b], p[1][c], p[2][b], p[2][c], sb, sc);
  const double e1 = edge(p[2][b], p[2][c], p[0][b], p[0][c], sb, sc);
  const double e2 = edge(p[0][b], p[0][c], p[1][b], p[1][c], sb, sc);
  const bool any_negative = e0 < 0 || e1 < 0 || e2 < 0;
  const bool any_positive = e0 > 0 || e1 > 0 || e2 > 0;
  if (any_negative == any_positive) return {};
  if (e0 == 0.0 || e1 == 0.0 || e2 == 0.0) return {LineCrossing::kDoubtful};
  const double sum = e0 + e1 + e2;
  return {LineCrossing::kHit, (e0 * p[0][axis] + e1 * p[1][axis] + e2 * p[2][axis]) / sum, sum > 0 ? 1 : -1};
}

// Counts crossings along rays parallel to `axis` through every voxel's sample point and
// clears `inside` where the point is outside: winding number 0 (signed crossings, for a
// consistently oriented mesh: inside any of several overlapping closed parts counts), else
// even parity. Voxels whose ray passes exactly through an edge or vertex are cleared too.
void vote_inside(const Grid& g, const Mesh& mesh, int axis, bool winding,
                 std::vector<uint8_t>& inside) {
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  struct Hit {
    double at;
    int sign;
    bool operator<(const Hit& o) const { return at < o.at; }
  };
  std::vector<std::vector<Hit>> hits(size_t(g.n) * g.n);
  std::vector<uint8_t> doubtful(size_t(g.n) * g.n, 0);
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    std::array<glm::dvec3, 3> p;
    for (int v = 0; v < 3; ++v) p[v] = glm::dvec3(mesh.positions[mesh.indices[t + v]]);
    const double lo_b = std::min({p[0][b], p[1][b], p[2][b]});
    const double hi_b = std::max({p[0][b], p[1][b], p[2][b]});
    const double lo_c = std::min({p[0][c], p[1][c], p[2][c]});
    const double hi_c = std::max({p[0][c], p[1][c], p[2][c]});
    const int i0 = std::max(0, int(std::ceil((lo_b - g.origin[b]) / g.voxel[b] - Grid::kSampleOffset[b])));
    const int j0 = std::max(0, int(std::ceil((lo_c - g.origin[c]) / g.voxel[c] - Grid::kSampleOffset[c])));
    for (int j = j0; j < g.n && g.sample(c, j) <= hi_c; ++j)
      for (int i = i0; i < g.n && g.sample(b, i) <= hi_b; ++i) {
        const LineCrossing x = line_crossing(p, axis, g.sample(b, i), g.sample(c, j));
        const size_t column = size_t(j) * g.n + i;
        if (x.kind == LineCrossing::kDoubtful) doubtful[column] = 1;  // the count would be a guess
        if (x.kind == LineCrossing::kHit) hits[column].push_back({x.at, winding ? x.sign : 1});
      }
  }
  for (int j = 0; j < g.n; ++j)
    for (int i = 0; i < g.n; ++i) {
      const size_t column = size_t(j) * g.n + i;
      std::vector<Hit>& h = hits[column];
      std::sort(h.begin(), h.end());
      size_t crossed = 0;
      int count = 0;  // signed crossings (winding) or crossings (parity) before the sample
      for (int k = 0; k < g.n; ++k) {
        const double s = g.sample(axis, k);
        for (; crossed < h.size() && h[crossed].at < s; ++crossed) count += h[crossed].sign;
        const bool exact = crossed < h.size() && h[crossed].at == s;
        Cell cell;
        cell[axis] = k, cell[b] = i, cell[c] = j;
        const size_t v = g.index(cell[0], cell[1], cell[2]);
        const bool outside = winding ? count == 0 : count % 2 == 0;
        if (doubtful[column] || exact || outside) inside[v] = 0;
      }
    }
}

// Chessboard distance (in voxels) from each interior voxel to the nearest non-interior one
// or the grid's outside; two raster passes over the 26-neighbourhood.
std::vector<int> chessboard_distance(const Grid& g, const std::vector<uint8_t>& interior) {
  std::vector<int> d(g.size());
  for (size_t v = 0; v < d.size(); ++v) d[v] = interior[v] ? g.n : 0;
  auto relax = [&](int i, int j, int k, int sign) {
    int& here = d[g.index(i, j, k)];
    if (here == 0) return;
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const int order = dk * 9 + dj * 3 + di;  // neighbours already visited in this pass
          if (order * sign >= 0) continue;
          const int ni = i + di, nj = j + dj, nk = k + dk;
          const bool outside = ni < 0 || nj < 0 || nk < 0 || ni >= g.n || nj >= g.n || nk >= g.n;
          here = std::min(here, 1 + (outside ? 0 : d[g.index(ni, nj, nk)]));
        }
  };
  for (int k = 0; k < g.n; ++k)
    for (int j = 0; j < g.n; ++j)
      for (int i = 0; i < g.n; ++i) relax(i, j, k, +1);
  for (int k = g.n - 1; k >= 0; --k)
    for (int j = g.n - 1; j >= 0; --j)
      for (int i = g.n - 1; i >= 0; --i) relax(i, j, k, -1);
  return d;
}

struct VoxelBox {
  Cell lo, hi;  // inclusive
};

bool all_interior(const Grid& g, const std::vector<uint8_t>& interior, const VoxelBox& box) {
  for (int k = box.lo[2]; k <= box.hi[2]; ++k)
    for (int j = box.lo[1]; j <= box.hi[1]; ++j)
      for (int i = box.lo[0]; i <= box.hi[0]; ++i)
        if (!interior[g.index(i, j, k)]) return false;
  return true;
}

// Grows the box one layer at a time, round robin over its six faces, while the new layer is
// interior: a maximal (not maximum) inscribed box, balanced in its proportions.
VoxelBox grow(const Grid& g, const std::vector<uint8_t>& interior, VoxelBox box) {
  for (bool grew = true; grew;) {
    grew = false;
    for (int face = 0; face < 6; ++face) {
      const int axis = face / 2;
      VoxelBox layer = box;
      if (face % 2 == 0) {
        if (box.lo[axis] == 0) continue;
        layer.lo[axis] = layer.hi[axis] = box.lo[axis] - 1;
      } else {
        if (box.hi[axis] == g.n - 1) continue;
        layer.lo[axis] = layer.hi[axis] = box.hi[axis] + 1;
      }
      if (!all_interior(g, interior, layer)) continue;
      (face % 2 == 0 ? box.lo : box.hi)[axis] = layer.lo[axis];
      grew = true;
    }
  }
  return box;
}

size_t cover(const Grid& g, const VoxelBox& box, std::vector<uint8_t>& covered) {
  size_t gained = 0;
  for (int k = box.lo[2]; k <= box.hi[2]; ++k)
    for (int j = box.lo[1]; j <= box.hi[1]; ++j)
      for (int i = box.lo[0]; i <= box.hi[0]; ++i) {
        uint8_t& c = covered[g.index(i, j, k)];
        gained += c == 0;
        c = 1;
      }
  return gained;
}

Aabb world_box(const Grid& g, const VoxelBox& box) {
  Aabb out;
  for (int a = 0; a < 3; ++a) {
    // Interior voxels keep 1e-3 voxel from every triangle; give up half of it to rounding.
    const double margin = g.voxel[a] * 5e-4;
    out.min[a] = float(g.origin[a] + box.lo[a] * g.voxel[a] + margin);
    out.max[a] = float(g.origin[a] + (box.hi[a] + 1) * g.voxel[a] - margin);
  }
  return out;
}

// Pushes each face of an interior box out to the nearest triangle whose box reaches over the
// face. Invariant: no triangle's box meets the open box, so the open box has one parity
// (odd: it holds interior voxels) and the closed box lies in the closed solid. A triangle
// whose box only touches the face's rectangle at its rim cannot enter the open box, so faces
// end exactly on axis-aligned walls and the boxes of abutting objects touch (and bridge).
Aabb extend_to_surface(const Mesh& mesh, Aabb box) {
  const Aabb bounds = bounds_of(mesh);
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2, u = (axis + 1) % 3, w = (axis + 2) % 3;
    const bool up = face % 2 == 1;
    float reach = (up ? bounds.max : bounds.min)[axis];
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
      Aabb tri;
      for (int v = 0; v < 3; ++v) tri.extend(mesh.positions[mesh.indices[t + v]]);
      const bool over = tri.min[u] < box.max[u] && tri.max[u] > box.min[u] &&
                        tri.min[w] < box.max[w] && tri.max[w] > box.min[w];
      const bool beyond = up ? tri.max[axis] > box.max[axis] : tri.min[axis] < box.min[axis];
      if (!over || !beyond) continue;
      reach = up ? std::min(reach, tri.min[axis]) : std::max(reach, tri.max[axis]);
    }
    (up ? box.max : box.min)[axis] =
        up ? std::max(box.max[axis], reach) : std::min(box.min[axis], reach);
  }
  return box;
}

std::vector<Aabb> boxes_in(const Grid& g, const std::vector<uint8_t>& interior,
                           const OccluderParams& params) {
  const std::vector<int> distance = chessboard_distance(g, interior);
  const size_t interior_count = size_t(std::count(interior.begin(), interior.end(), 1));
  std::vector<uint8_t> covered(g.size(), 0);
  std::vector<Aabb> out;
  while (int(out.size()) < params.max_boxes) {
    size_t seed = g.size();
    for (size_t v = 0; v < g.size(); ++v)
      if (!covered[v] && distance[v] > 0 && (seed == g.size() || distance[v] > distance[seed]))
        seed = v;
    if (seed == g.size()) break;
    const Cell at{int(seed % g.n), int(seed / g.n % g.n), int(seed / (size_t(g.n) * g.n))};
    const int r = distance[seed] - 1;  // the cube of this radius is interior
    VoxelBox box{{at[0] - r, at[1] - r, at[2] - r}, {at[0] + r, at[1] + r, at[2] + r}};
    box = grow(g, interior, box);
    std::vector<uint8_t> trial = covered;
    const size_t gained = cover(g, box, trial);
    if (!out.empty() && double(gained) < params.min_gain * double(interior_count)) break;
    covered.swap(trial);
    out.push_back(world_box(g, box));
  }
  return out;
}

}  // namespace

bool is_oriented(const Mesh& mesh) {
  const std::vector<uint32_t> id = welded_ids(mesh);
  std::vector<std::pair<uint64_t, int>> edges;
  edges.reserve(mesh.indices.size());
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = id[mesh.indices[t + e]], b = id[mesh.indices[t + (e + 1) % 3]];
      if (a != b) edges.push_back({uint64_t(std::min(a, b)) << 32 | std::max(a, b), a < b ? 1 : -1});
    }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i < edges.size();) {
    int sum = 0;
    size_t j = i;
    for (; j < edges.size() && edges[j].first == edges[i].first; ++j) sum += edges[j].second;
    if (sum != 0) return false;
    i = j;
  }
  return true;
}

bool is_closed(const Mesh& mesh) {
  const std::vector<uint32_t> id = welded_ids(mesh);
  std::vector<uint64_t> edges;
  edges.reserve(mesh.indices.size());
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = id[mesh.indices[t + e]], b = id[mesh.indices[t + (e + 1) % 3]];
      if (a != b) edges.push_back(uint64_t(std::min(a, b)) << 32 | std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if ((j - i) % 2 != 0) return false;
    i = j;
  }
  return !edges.empty();
}

namespace {

// Three orthonormal directions in no special position: lines along them through a point of
// a generated world (regular coordinates, cubes and quads split along their diagonals, cell
// corners pulled in equally along every axis) practically never pass through an edge.
const std::array<glm::dvec3, 3>& probe_directions() {
  static const std::array<glm::dvec3, 3> directions = [] {
    const glm::dvec3 a = glm::normalize(glm::dvec3(1.0, 0.3137, 0.2071));
    const glm::dvec3 b = glm::normalize(glm::cross(a, glm::dvec3(0.1713, 1.0, 0.4271)));
    return std::array<glm::dvec3, 3>{a, b, glm::cross(a, b)};
  }();
  return directions;
}

}  // namespace

bool solid_at(std::span<const Vec3> positions, std::span<const uint32_t> indices, const Vec3& point,
              bool winding) {
  const glm::dvec3 q(point);
  const std::array<glm::dvec3, 3>& frame = probe_directions();
  std::array<int, 3> ahead{}, behind{};  // per direction: crossings beyond q and before it
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    std::array<glm::dvec3, 3> p;  // the triangle in the frame, q at the origin
    for (int v = 0; v < 3; ++v) {
      const glm::dvec3 r = glm::dvec3(positions[indices[t + v]]) - q;
      p[v] = {glm::dot(frame[0], r), glm::dot(frame[1], r), glm::dot(frame[2], r)};
    }
    for (int axis = 0; axis < 3; ++axis) {
      const LineCrossing x = line_crossing(p, axis, 0.0, 0.0);
      if (x.kind == LineCrossing::kMiss) continue;
      if (x.kind == LineCrossing::kDoubtful || x.at == 0.0) return false;  // a guess, or q on it
      (x.at > 0.0 ? ahead : behind)[axis] += winding ? x.sign : 1;
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    // Along a whole line a cycle's crossings cancel (winding) or pair up (parity): the two rays
    // from q must agree, else rounding has split a crossing, or the mesh is not closed.
    const bool agree = winding ? ahead[axis] == -behind[axis] : (ahead[axis] - behind[axis]) % 2 == 0;
    const bool inside = winding ? ahead[axis] != 0 : ahead[axis] % 2 != 0;
    if (!agree || !inside) return false;
  }
  return true;
}

namespace {

// Triangles grouped into connected components (sharing welded vertices), each as its own
// compact mesh. Generated and modelled objects are assemblies of overlapping closed parts:
// the faces of one part that lie inside another cut the whole mesh's interior into slices
// (floors between floor slabs, walls lined with window boxes), but each part alone is a clean
// solid.
std::vector<Mesh> components_of(const Mesh& mesh) {
  const std::vector<uint32_t> id = welded_ids(mesh);
  std::vector<uint32_t> parent(mesh.positions.size());
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  auto root = [&](uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
    for (int e = 1; e < 3; ++e) parent[root(id[mesh.indices[t + e]])] = root(id[mesh.indices[t]]);
  std::unordered_map<uint32_t, size_t> component;  // root -> index in out
  std::vector<Mesh> out;
  std::vector<std::unordered_map<uint32_t, uint32_t>> remap;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t r = root(id[mesh.indices[t]]);
    const auto [it, added] = component.emplace(r, out.size());
    if (added) out.emplace_back(), remap.emplace_back();
    Mesh& m = out[it->second];
    for (int v = 0; v < 3; ++v) {
      const uint32_t source = mesh.indices[t + v];
      const auto [at, fresh] = remap[it->second].emplace(source, uint32_t(m.positions.size()));
      if (fresh) m.positions.push_back(mesh.positions[source]);
      m.indices.push_back(at->second);
    }
  }
  return out;
}

// The inscribed boxes of one closed mesh, on its own classification grid.
std::vector<Aabb> boxes_of_solid(const Mesh& mesh, const OccluderParams& params) {
  const Aabb bounds = bounds_of(mesh);
  Grid g;
  g.n = params.grid;
  for (int a = 0; a < 3; ++a) {
    g.origin[a] = bounds.min[a];
    g.voxel[a] = (double(bounds.max[a]) - double(bounds.min[a])) / g.n;
    if (!(g.voxel[a] > 0.0)) return {};  // flat: no volume to stand in for
  }
  std::vector<uint8_t> surface(g.size(), 0);
  mark_surface(g, mesh, surface);
  std::vector<uint8_t> interior(g.size(), 1);
  const bool winding = is_oriented(mesh);
  for (int axis = 0; axis < 3; ++axis) vote_inside(g, mesh, axis, winding, interior);
  for (size_t v = 0; v < g.size(); ++v) interior[v] = interior[v] && !surface[v];
  std::vector<Aabb> out;
  for (const Aabb& box : boxes_in(g, interior, params)) out.push_back(extend_to_surface(mesh, box));
  return out;
}

double volume(const Aabb& b) {
  const Vec3 s = glm::max(b.size(), Vec3(0.0f));
  return double(s.x) * s.y * s.z;
}

// A closed part all of whose triangles lie in the faces of its bounding box bounds that box or
// nothing: a cycle of triangles on a box's surface is k times the whole surface (one class, as
// on a sphere), and k is the winding number (oriented) or parity anywhere inside the open box.
// k = 0 is the common case of open surfaces written double-sided (each triangle twice, in
// opposite windings: an L of two walls, a room with a door), which pass the closedness test
// but enclose nothing. So one point inside must be solid; an unoriented part, or one whose
// point test is in doubt, is left to the voxel classification.
std::optional<Aabb> box_part(const Mesh& part) {
  const Aabb b = bounds_of(part);
  if (!(volume(b) > 0.0) || !is_oriented(part)) return std::nullopt;
  for (size_t t = 0; t + 2 < part.indices.size(); t += 3) {
    bool on_face = false;
    for (int a = 0; a < 3 && !on_face; ++a)
      for (const float side : {b.min[a], b.max[a]}) {
        bool all = true;
        for (int v = 0; v < 3; ++v) all = all && part.positions[part.indices[t + v]][a] == side;
        on_face = on_face || all;
      }
    if (!on_face) return std::nullopt;
  }
  if (!solid_at(part.positions, part.indices, b.center(), true)) return std::nullopt;
  return b;
}

std::vector<Aabb> boxes_of_closed(const Mesh& mesh, const OccluderParams& params) {
  const std::optional<Aabb> whole = box_part(mesh);
  return whole ? std::vector<Aabb>{*whole} : boxes_of_solid(mesh, params);
}

// The mesh less one triangle of each pair of twins (the same three welded vertices in opposite
// windings, as exporters write double-sided surfaces); nullopt when there is no pair. Twins
// cover the same points, so the opaque surface is unchanged; but the pair adds nothing to
// the cycle (winding number and parity), and one side alone bounds what the surface encloses.
std::optional<Mesh> one_side_of_twins(const Mesh& mesh) {
  const std::vector<uint32_t> id = welded_ids(mesh);
  // The welded ids rotated to start at the smallest: equal for the same winding.
  const auto key = [](uint32_t a, uint32_t b, uint32_t c) {
    if (b < a && b <= c) return std::array<uint32_t, 3>{b, c, a};
    if (c < a && c < b) return std::array<uint32_t, 3>{c, a, b};
    return std::array<uint32_t, 3>{a, b, c};
  };
  std::map<std::array<uint32_t, 3>, size_t> unmatched;  // triangles still waiting for a twin
  std::vector<uint8_t> dropped(mesh.triangle_count(), 0);
  bool any = false;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const uint32_t a = id[mesh.indices[3 * t]], b = id[mesh.indices[3 * t + 1]], c = id[mesh.indices[3 * t + 2]];
    const auto twin = unmatched.find(key(a, c, b));
    if (twin != unmatched.end() && twin->second > 0) {
      --twin->second;
      dropped[t] = 1;
      any = true;
    } else {
      ++unmatched[key(a, b, c)];
    }
  }
  if (!any) return std::nullopt;
  Mesh out;
  out.positions = mesh.positions;
  for (size_t t = 0; t < mesh.triangle_count(); ++t)
    if (!dropped[t]) out.indices.insert(out.indices.end(), mesh.indices.begin() + 3 * t, mesh.indices.begin() + 3 * t + 3);
  return out;
}

// The boxes of one closed part. A part that gives none and holds twins is tried again with one
// side of each: a double-sided closed box (winding number 0) is then the box it looks like,
// while an L of double-sided walls or a room with a door is open and still gives none. Sound
// either way: a solid bounded by some of the drawn triangles is enclosed by them.
std::vector<Aabb> boxes_of_part(const Mesh& part, const OccluderParams& params) {
  std::vector<Aabb> out = boxes_of_closed(part, params);
  if (!out.empty()) return out;
  const std::optional<Mesh> one_side = one_side_of_twins(part);
  return one_side && is_closed(*one_side) ? boxes_of_closed(*one_side, params) : out;
}

// The largest boxes first, up to max_boxes, each at least min_gain of the largest's volume
// and not inside one already kept.
std::vector<Aabb> largest_boxes(std::vector<Aabb> candidates, const OccluderParams& params) {
  std::sort(candidates.begin(), candidates.end(),
            [](const Aabb& a, const Aabb& b) { return volume(a) > volume(b); });
  std::vector<Aabb> out;
  for (const Aabb& box : candidates) {
    if (int(out.size()) == params.max_boxes) break;
    if (!out.empty() && volume(box) < params.min_gain * volume(out.front())) break;
    if (std::none_of(out.begin(), out.end(), [&](const Aabb& kept) { return kept.contains(box); }))
      out.push_back(box);
  }
  return out;
}

}  // namespace

InscribedBoxes inscribed_boxes(const Mesh& mesh, const OccluderParams& params) {
  InscribedBoxes out;
  out.closed = is_closed(mesh);
  if (params.grid < 1) return out;
  // Each closed part bounds a solid of its own (the crossing argument holds part by part);
  // a mesh whose parts close only together is classified whole. Parts are taken largest
  // first; one whose bounding box is smaller than min_gain of the largest box found cannot
  // give a box that would be kept, so it is not classified (window frames, railings).
  std::vector<Mesh> parts = components_of(mesh);
  std::vector<std::pair<double, size_t>> order;
  for (size_t i = 0; i < parts.size(); ++i) order.push_back({volume(bounds_of(parts[i])), i});
  std::sort(order.begin(), order.end(), std::greater<>());
  std::vector<Aabb> candidates;
  double largest = 0.0;
  bool any_closed_part = false;
  for (const auto& [part_volume, i] : order) {
    if (part_volume < params.min_gain * largest || !is_closed(parts[i])) continue;
    any_closed_part = true;
    for (const Aabb& b : boxes_of_part(parts[i], params)) {
      candidates.push_back(b);
      largest = std::max(largest, volume(b));
    }
  }
  if (!any_closed_part && out.closed) candidates = boxes_of_solid(mesh, params);
  out.boxes = largest_boxes(std::move(candidates), params);
  return out;
}

std::vector<Aabb> bridge_boxes(const Aabb& a, const Aabb& b) {
  std::vector<Aabb> out;
  if (!a.overlaps(b)) return out;
  const Aabb common{glm::max(a.min, b.min), glm::min(a.max, b.max)};
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    if (!(common.min[u] < common.max[u] && common.min[w] < common.max[w])) continue;
    Aabb bridge = common;
    bridge.min[axis] = std::min(a.min[axis], b.min[axis]);
    bridge.max[axis] = std::max(a.max[axis], b.max[axis]);
    if (!a.contains(bridge) && !b.contains(bridge)) out.push_back(bridge);
  }
  return out;
}

bool segment_meets_box(const Vec3& a, const Vec3& b, const Aabb& box) {
  double t0 = 0.0, t1 = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double from = a[axis], d = double(b[axis]) - from;
    const double lo = box.min[axis], hi = box.max[axis];
    if (d == 0.0) {
      if (from < lo || from > hi) return false;
      continue;
    }
    double near = (lo - from) / d, far = (hi - from) / d;
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
    if (t0 > t1) return false;
  }
  return true;
}

namespace {
double largest_magnitude(const Vec3& lo, const Vec3& hi) {
  const Vec3 m = glm::max(glm::abs(lo), glm::abs(hi));
  return double(std::max({m.x, m.y, m.z}));
}
}  // namespace

SegmentFilter::SegmentFilter(const Vec3& a, const Vec3& b) : from_(a) {
  const glm::dvec3 d = glm::dvec3(b) - from_;
  for (int axis = 0; axis < 3; ++axis) {
    moves_[axis] = d[axis] != 0.0;
    inverse_[axis] = moves_[axis] ? 1.0 / d[axis] : 0.0;
  }
  pad_ = 1e-6 * largest_magnitude(a, b) + 1e-9;
}

// A box of coordinates much larger than the segment's gets a larger pad from its own.
bool SegmentFilter::may_meet(const Aabb& box) const {
  const double pad = pad_ + 1e-6 * largest_magnitude(box.min, box.max);
  double t0 = 0.0, t1 = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double lo = double(box.min[axis]) - pad, hi = double(box.max[axis]) + pad;
    if (!moves_[axis]) {
      if (from_[axis] < lo || from_[axis] > hi) return false;
      continue;
    }
    double near = (lo - from_[axis]) * inverse_[axis], far = (hi - from_[axis]) * inverse_[axis];
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
    if (t0 > t1) return false;
  }
  return true;
}

bool occluder_hides(const Aabb& cell, const Aabb& occluder, const Aabb& occludee) {
  auto corner = [](const Aabb& b, int i) {
    return Vec3(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z);
  };
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j)
      if (!segment_meets_box(corner(cell, i), corner(occludee, j), occluder)) return false;
  return true;
}

}  // namespace cellwalk::visibility
