// Not from one seed [ours], for issue 15: an indoor level as game editors write one, to
// measure visibility on geometry that is closed only all together (vLOD §5.2.2's occluders
// must then come from the surfaces, docs/surface-occluders.md). Rooms on a grid joined by
// corridors, carved out of solid: every floor, wall and ceiling a single-sided face facing
// into the open space, one object each, tiled into small quads as level editors tessellate;
// closed crates on the floors.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <tuple>
#include <utility>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/scene/generators.hpp"
#include "scene/shapes.hpp"

namespace cellwalk {
namespace {

constexpr float kPitch = 10.0f;     // room slots, metres
constexpr float kEyeHeight = 1.6f;
constexpr float kInset = 0.3f;      // nav nodes this far inside a room from a corridor's mouth

// The carve grid: every box coordinate per axis, sorted, and which grid cells are open.
struct CarveGrid {
  std::array<std::vector<float>, 3> at;
  std::array<int, 3> n{};
  std::vector<uint8_t> open;

  explicit CarveGrid(const std::vector<Aabb>& spaces) {
    for (const Aabb& s : spaces)
      for (int a = 0; a < 3; ++a) at[a].insert(at[a].end(), {s.min[a], s.max[a]});
    for (int a = 0; a < 3; ++a) {
      std::sort(at[a].begin(), at[a].end());
      at[a].erase(std::unique(at[a].begin(), at[a].end()), at[a].end());
      n[a] = std::max(0, int(at[a].size()) - 1);
    }
    open.assign(size_t(n[0]) * size_t(n[1]) * size_t(n[2]), 0);
    for (const Aabb& s : spaces) {
      std::array<int, 3> lo, hi;
      for (int a = 0; a < 3; ++a) {
        lo[a] = int(std::lower_bound(at[a].begin(), at[a].end(), s.min[a]) - at[a].begin());
        hi[a] = int(std::lower_bound(at[a].begin(), at[a].end(), s.max[a]) - at[a].begin());
      }
      for (int k = lo[2]; k < hi[2]; ++k)
        for (int j = lo[1]; j < hi[1]; ++j)
          for (int i = lo[0]; i < hi[0]; ++i) open[index({i, j, k})] = 1;
    }
  }
  size_t index(const std::array<int, 3>& c) const { return (size_t(c[2]) * size_t(n[1]) + size_t(c[1])) * size_t(n[0]) + size_t(c[0]); }
  bool is_open(const std::array<int, 3>& c) const {
    for (int a = 0; a < 3; ++a)
      if (c[a] < 0 || c[a] >= n[a]) return false;
    return open[index(c)] != 0;
  }
};

// A face before tessellation: [u0, u1] × [w0, w1] in the plane `axis` = `plane`, facing
// +axis when `up` (u = axis + 1, w = axis + 2, cyclically).
struct Rect {
  int axis;
  float plane;
  bool up;
  float u0, u1, w0, w1;
};

// An axis-aligned line: its direction and its two other coordinates, in axis order.
using LineKey = std::tuple<int, float, float>;

LineKey line_of(int direction, int axis, float plane, int other, float at) {
  const float first = axis < other ? plane : at, second = axis < other ? at : plane;
  return {direction, first, second};
}

// Every rectangle's corners, by the lines its edges lie on: where an edge of another face
// must be split so that no vertex lies inside an edge (a T-junction, where the rasteriser
// leaves cracks between faces that meet).
using LineEnds = std::map<LineKey, std::vector<float>>;

void add_edges(const Rect& r, LineEnds& ends) {
  const int u = (r.axis + 1) % 3, w = (r.axis + 2) % 3;
  for (float at : {r.w0, r.w1}) {
    auto& v = ends[line_of(u, r.axis, r.plane, w, at)];
    v.insert(v.end(), {r.u0, r.u1});
  }
  for (float at : {r.u0, r.u1}) {
    auto& v = ends[line_of(w, r.axis, r.plane, u, at)];
    v.insert(v.end(), {r.w0, r.w1});
  }
}

// The ends on `line` strictly between lo and hi, ascending.
std::vector<float> ends_between(const LineEnds& ends, const LineKey& line, float lo, float hi) {
  std::vector<float> out;
  if (auto it = ends.find(line); it != ends.end())
    for (float e : it->second)
      if (e > lo && e < hi) out.push_back(e);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// lo, hi and the multiples of `tile` between them (one world-wide lattice, so faces that share
// an edge split it at the same lattice points).
std::vector<float> lattice(float lo, float hi, double tile) {
  std::vector<float> out{lo};
  if (tile > 0)
    for (double k = std::floor(lo / tile) + 1; k * tile < hi; ++k)
      if (float(k * tile) > lo && float(k * tile) < hi) out.push_back(float(k * tile));
  out.push_back(hi);
  return out;
}

// The rectangle as quads on the lattice; a quad on the rectangle's rim also takes the corners
// of other faces that lie inside its rim side, and is then a fan around its centre.
Mesh tessellated(const Rect& r, const LineEnds& ends, double tile) {
  const int u = (r.axis + 1) % 3, w = (r.axis + 2) % 3;
  const std::vector<float> us = lattice(r.u0, r.u1, tile), ws = lattice(r.w0, r.w1, tile);
  Mesh m;
  std::map<std::pair<float, float>, uint32_t> index;
  Vec3 normal(0.0f);
  normal[r.axis] = r.up ? 1.0f : -1.0f;
  auto vertex = [&](float a, float b) {
    auto [it, added] = index.emplace(std::make_pair(a, b), uint32_t(m.positions.size()));
    if (added) {
      Vec3 p;
      p[r.axis] = r.plane;
      p[u] = a;
      p[w] = b;
      m.positions.push_back(p);
      m.normals.push_back(normal);
    }
    return it->second;
  };
  auto triangle = [&](uint32_t a, uint32_t b, uint32_t c) {
    // Counter-clockwise in (u, w) faces +axis: cross(e_u, e_w) = e_axis.
    if (r.up)
      m.indices.insert(m.indices.end(), {a, b, c});
    else
      m.indices.insert(m.indices.end(), {a, c, b});
  };
  for (size_t b = 0; b + 1 < ws.size(); ++b)
    for (size_t a = 0; a + 1 < us.size(); ++a) {
      const float ua = us[a], ub = us[a + 1], wa = ws[b], wb = ws[b + 1];
      std::vector<std::pair<float, float>> ring{{ua, wa}};
      auto side = [&](bool on_rim, const LineKey& line, float lo, float hi, bool forward, bool along_u, float fixed) {
        if (!on_rim) return;
        std::vector<float> e = ends_between(ends, line, lo, hi);
        if (!forward) std::reverse(e.begin(), e.end());
        for (float x : e) ring.push_back(along_u ? std::make_pair(x, fixed) : std::make_pair(fixed, x));
      };
      side(b == 0, line_of(u, r.axis, r.plane, w, wa), ua, ub, true, true, wa);
      ring.push_back({ub, wa});
      side(a + 2 == us.size(), line_of(w, r.axis, r.plane, u, ub), wa, wb, true, false, ub);
      ring.push_back({ub, wb});
      side(b + 2 == ws.size(), line_of(u, r.axis, r.plane, w, wb), ua, ub, false, true, wb);
      ring.push_back({ua, wb});
      side(a == 0, line_of(w, r.axis, r.plane, u, ua), wa, wb, false, false, ua);
      if (ring.size() == 4) {
        triangle(vertex(ua, wa), vertex(ub, wa), vertex(ub, wb));
        triangle(vertex(ua, wa), vertex(ub, wb), vertex(ua, wb));
        continue;
      }
      const uint32_t centre = vertex(0.5f * (ua + ub), 0.5f * (wa + wb));
      for (size_t i = 0; i < ring.size(); ++i) {
        const auto& p = ring[i];
        const auto& q = ring[(i + 1) % ring.size()];
        triangle(centre, vertex(p.first, p.second), vertex(q.first, q.second));
      }
    }
  return m;
}

// The faces of one plane and facing, merged greedily into maximal rectangles.
void faces_of_plane(const CarveGrid& g, int axis, int plane, bool up, std::vector<Rect>& out) {
  const int u = (axis + 1) % 3, w = (axis + 2) % 3;
  std::vector<uint8_t> face(size_t(g.n[u]) * size_t(g.n[w]), 0);
  bool any = false;
  for (int b = 0; b < g.n[w]; ++b)
    for (int a = 0; a < g.n[u]; ++a) {
      std::array<int, 3> inside{}, beyond{};
      inside[axis] = up ? plane : plane - 1;
      beyond[axis] = up ? plane - 1 : plane;
      inside[u] = beyond[u] = a;
      inside[w] = beyond[w] = b;
      face[size_t(b) * g.n[u] + a] = g.is_open(inside) && !g.is_open(beyond);
      any = any || face[size_t(b) * g.n[u] + a];
    }
  if (!any) return;
  for (int b = 0; b < g.n[w]; ++b)
    for (int a = 0; a < g.n[u]; ++a) {
      if (!face[size_t(b) * g.n[u] + a]) continue;
      int a1 = a;
      while (a1 + 1 < g.n[u] && face[size_t(b) * g.n[u] + a1 + 1]) ++a1;
      int b1 = b;
      auto row_full = [&](int row) {
        for (int x = a; x <= a1; ++x)
          if (!face[size_t(row) * g.n[u] + x]) return false;
        return true;
      };
      while (b1 + 1 < g.n[w] && row_full(b1 + 1)) ++b1;
      for (int y = b; y <= b1; ++y)
        for (int x = a; x <= a1; ++x) face[size_t(y) * g.n[u] + x] = 0;
      out.push_back({axis, g.at[axis][plane], up, g.at[u][a], g.at[u][a1 + 1], g.at[w][b], g.at[w][b1 + 1]});
    }
}

struct Room {
  Aabb box;
  Vec3 centre;  // nav node
};

Room make_room(int i, int j, Random& rng) {
  const float sx = float(rng.uniform(4, 8)), sz = float(rng.uniform(4, 8)), h = float(rng.uniform(3, 4));
  // Centres within 0.5 m of the slot's: neighbours overlap by at least 3 m across a corridor.
  const float cx = (float(i) + 0.5f) * kPitch + float(rng.uniform(-0.5, 0.5));
  const float cz = (float(j) + 0.5f) * kPitch + float(rng.uniform(-0.5, 0.5));
  return {{{cx - sx / 2, 0, cz - sz / 2}, {cx + sx / 2, h, cz + sz / 2}}, {cx, kEyeHeight, cz}};
}

// A straight corridor from room a to room b, its neighbour along `axis` (0: x, 2: z), with a
// nav path a's centre → mouth in a → mouth in b → b's centre.
Aabb corridor(const Room& a, const Room& b, int axis, Random& rng, NavGraph& nav, uint32_t node_a, uint32_t node_b) {
  const int across = 2 - axis;
  const float lo = std::max(a.box.min[across], b.box.min[across]), hi = std::min(a.box.max[across], b.box.max[across]);
  const float width = float(rng.uniform(1.2, 2.0));
  const float start = float(rng.uniform(lo + 0.2, hi - 0.2 - width));
  Aabb c;
  c.min = Vec3(0.0f);
  c.max = Vec3(0.0f, float(rng.uniform(2.2, 2.6)), 0.0f);
  c.min[axis] = a.box.max[axis];
  c.max[axis] = b.box.min[axis];
  c.min[across] = start;
  c.max[across] = start + width;
  Vec3 mouth_a(0, kEyeHeight, 0), mouth_b(0, kEyeHeight, 0);
  mouth_a[across] = mouth_b[across] = start + width / 2;
  mouth_a[axis] = a.box.max[axis] - kInset;
  mouth_b[axis] = b.box.min[axis] + kInset;
  const uint32_t first = uint32_t(nav.nodes.size());
  nav.nodes.push_back(mouth_a);
  nav.nodes.push_back(mouth_b);
  nav.edges.emplace_back(node_a, first);
  nav.edges.emplace_back(first, first + 1);
  nav.edges.emplace_back(first + 1, node_b);
  return c;
}

}  // namespace

std::vector<CarvedFace> carved_faces(const std::vector<Aabb>& spaces, double tile) {
  const CarveGrid g(spaces);
  std::vector<Rect> rects;
  for (int axis = 0; axis < 3; ++axis)
    for (int plane = 0; plane <= g.n[axis]; ++plane)
      for (bool up : {true, false}) faces_of_plane(g, axis, plane, up, rects);
  LineEnds ends;
  for (const Rect& r : rects) add_edges(r, ends);
  std::vector<CarvedFace> out;
  for (const Rect& r : rects) {
    Vec3 normal(0.0f);
    normal[r.axis] = r.up ? 1.0f : -1.0f;
    out.push_back({tessellated(r, ends, tile), normal});
  }
  return out;
}

SceneInfo generate_level(const LevelParams& params, ObjectSink& sink) {
  if (params.rooms_x < 1 || params.rooms_z < 1) fail("level", "rooms_x and rooms_z must be at least 1");
  if (!(params.tile >= 0.0) || !std::isfinite(params.tile)) fail("level", "tile must be a finite number of metres >= 0");
  Random rng(params.seed);
  std::vector<Room> rooms;
  NavGraph nav;
  for (int j = 0; j < params.rooms_z; ++j)
    for (int i = 0; i < params.rooms_x; ++i) {
      Random r = rng.split(uint64_t(j) * 100003 + uint64_t(i));
      rooms.push_back(make_room(i, j, r));
      nav.nodes.push_back(rooms.back().centre);
    }
  std::vector<Aabb> spaces;
  for (const Room& r : rooms) spaces.push_back(r.box);
  // A spanning tree (each room joined to the one before it along x or z) and some loops.
  for (int j = 0; j < params.rooms_z; ++j)
    for (int i = 0; i < params.rooms_x; ++i) {
      Random r = rng.split((uint64_t(1) << 40) | (uint64_t(j) * 100003 + uint64_t(i)));
      const bool tree_along_x = j == 0 || (i > 0 && r.uniform() < 0.5);
      const uint32_t here = uint32_t(j * params.rooms_x + i);
      if (i > 0 && (tree_along_x || r.uniform() < 0.3))
        spaces.push_back(corridor(rooms[here - 1], rooms[here], 0, r, nav, here - 1, here));
      if (j > 0 && (!tree_along_x || r.uniform() < 0.3))
        spaces.push_back(corridor(rooms[here - uint32_t(params.rooms_x)], rooms[here], 2, r, nav, here - uint32_t(params.rooms_x), here));
    }
  SceneInfo info{"level", params.seed, {}, std::move(nav)};
  shapes::ObjectEmitter out(sink, info);
  int walls = 0, floors = 0, ceilings = 0;
  for (CarvedFace& f : carved_faces(spaces, params.tile)) {
    const bool floor = f.normal.y > 0.5f, ceiling = f.normal.y < -0.5f;
    const std::string name = floor ? "level/floor/" + std::to_string(floors++)
                             : ceiling ? "level/ceiling/" + std::to_string(ceilings++)
                                       : "level/wall/" + std::to_string(walls++);
    out.emit(name, floor ? rgba8(120, 95, 70) : ceiling ? rgba8(225, 225, 215) : rgba8(185, 180, 170), f.mesh);
  }
  for (size_t k = 0; k < rooms.size(); ++k) {
    Random r = rng.split((uint64_t(2) << 40) | k);
    const Aabb& room = rooms[k].box;
    for (int c = 0; c < params.crates; ++c) {
      const float s = float(r.uniform(0.4, 1.2)), h = float(r.uniform(0.4, 1.2));
      const float x = float(r.uniform(room.min.x + 0.3, room.max.x - 0.3 - s));
      const float z = float(r.uniform(room.min.z + 0.3, room.max.z - 0.3 - s));
      Mesh crate = shapes::box(Vec3(s, h, s));  // centred on the y axis
      transform(crate, shapes::Assembly::translate(Vec3(x + s / 2, 0, z + s / 2)));
      out.emit("level/room" + std::to_string(k) + "/crate" + std::to_string(c), rgba8(160, 110, 60), crate);
    }
  }
  return info;
}

}  // namespace cellwalk
