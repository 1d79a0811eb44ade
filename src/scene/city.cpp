// HDoV thesis (Shou 2002) §3.3 and Table 3.1: a synthetic cityscape made by duplicating base
// models — three houses, five towers (240 to 1,812 polygons) and the Stanford bunny (69,451) —
// on a grid with objects 10–30 m apart. The building models' source is not given, so ours are
// built from primitive shapes with tessellation chosen to match Table 3.1's polygon counts.
#include <cmath>
#include <string>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/core/random.hpp"
#include "scene/shapes.hpp"

namespace cellwalk {
namespace {

using shapes::Assembly;

constexpr float kPi = std::numbers::pi_v<float>;
constexpr double kEyeHeight = 1.7;
constexpr double kSetback = 1.0;  // between a lot's edge and what stands on it

// ---- Base models (Table 3.1). Footprints are in metres around the Y axis. --------------

// Thin boxes proud of the four walls of a w × d body: `floors` rows of `columns` per wall.
void add_windows(Assembly& a, float w, float d, float y0, float floor_height, int floors,
                 int columns) {
  for (int side = 0; side < 4; ++side) {
    const bool along_x = side % 2 == 0;
    const float wall = along_x ? w : d;
    const float offset = (along_x ? d : w) * 0.5f;
    const float sign = side < 2 ? 1.0f : -1.0f;
    for (int f = 0; f < floors; ++f)
      for (int c = 0; c < columns; ++c) {
        const float t = wall * ((c + 0.5f) / columns - 0.5f);
        const float y = y0 + floor_height * (f + 0.3f);
        const Vec3 size = along_x ? Vec3(wall / columns * 0.5f, floor_height * 0.45f, 0.15f)
                                  : Vec3(0.15f, floor_height * 0.45f, wall / columns * 0.5f);
        const Vec3 at = along_x ? Vec3(t, y, sign * offset) : Vec3(sign * offset, y, t);
        a.add(shapes::box(size), at);
      }
  }
}

Mesh house1() {  // a mansion with two wings, a porch and a turret
  Assembly a;
  a.add(shapes::box({14, 7, 10}), Vec3(0));
  a.add(shapes::pyramid({15, 4, 11}), Vec3(0, 7, 0));
  add_windows(a, 14, 10, 0, 3.5f, 2, 6);
  for (float side : {-1.0f, 1.0f}) {
    a.add(shapes::box({6, 5, 8}), Vec3(side * 10, 0, 0));
    a.add(shapes::pyramid({6.5f, 3, 8.5f}), Vec3(side * 10, 5, 0));
    Assembly wing;
    add_windows(wing, 6, 8, 0, 2.5f, 2, 4);
    a.add(wing.take(), Vec3(side * 10, 0, 0));
    a.add(shapes::box({1, 3, 1}), Vec3(side * 4, 7, 2));
  }
  for (int i = 0; i < 4; ++i) a.add(shapes::cylinder(0.3f, 3.5f, 12), Vec3(-4.5f + 3 * i, 0, 6));
  a.add(shapes::box({11, 0.4f, 2.5f}), Vec3(0, 3.5f, 6));
  a.add(shapes::cylinder(2, 10, 20), Vec3(-7, 0, -5));
  a.add(shapes::cone(2.4f, 4, 20), Vec3(-7, 10, -5));
  return a.take();
}

Mesh house2() {  // two storeys, hip roof, chimney and garage
  Assembly a;
  a.add(shapes::box({10, 6, 8}), Vec3(0));
  a.add(shapes::pyramid({11, 3.5f, 9}), Vec3(0, 6, 0));
  a.add(shapes::box({1, 3, 1}), Vec3(3, 7, 0));
  a.add(shapes::box({1.2f, 2.2f, 0.2f}), Vec3(0, 0, 4));
  add_windows(a, 10, 8, 0, 3, 2, 5);
  a.add(shapes::box({4, 3, 6}), Vec3(7, 0, 1));
  a.add(shapes::pyramid({4.4f, 1.5f, 6.4f}), Vec3(7, 3, 1));
  return a.take();
}

Mesh house3() {  // a one-storey cottage
  Assembly a;
  a.add(shapes::box({8, 3.5f, 7}), Vec3(0));
  a.add(shapes::pyramid({9, 3, 8}), Vec3(0, 3.5f, 0));
  a.add(shapes::box({0.8f, 2.5f, 0.8f}), Vec3(2, 4.5f, 1));
  a.add(shapes::box({1.2f, 2.2f, 0.2f}), Vec3(0, 0, 3.5f));
  add_windows(a, 8, 7, 0, 3.5f, 1, 4);
  return a.take();
}

Mesh tower1() {  // three set-back slabs with floor lines, window strips and a mast
  Assembly a;
  const float widths[] = {16, 12, 8}, heights[] = {20, 16, 12};
  const int strips[] = {3, 2, 2};
  float y = 0;
  for (int s = 0; s < 3; ++s) {
    a.add(shapes::box({widths[s], heights[s], widths[s]}), Vec3(0, y, 0));
    const int floors = static_cast<int>(heights[s] / 3.5f);
    for (int f = 1; f <= floors; ++f)
      a.add(shapes::box({widths[s] + 0.4f, 0.3f, widths[s] + 0.4f}),
            Vec3(0, y + 3.5f * f - 0.3f, 0));
    Assembly windows;
    add_windows(windows, widths[s], widths[s], 0, heights[s], 1, strips[s]);
    a.add(windows.take(), Vec3(0, y, 0));
    y += heights[s];
  }
  a.add(shapes::cylinder(0.3f, 10, 6), Vec3(0, y, 0));
  return a.take();
}

Mesh tower2() {  // a round tower with balcony rings and a spire
  Assembly a;
  a.add(shapes::box({18, 4, 18}), Vec3(0));
  a.add(shapes::cylinder(7, 45, 24), Vec3(0, 4, 0));
  for (int r = 1; r <= 9; ++r) a.add(shapes::cylinder(7.6f, 0.4f, 24), Vec3(0, 4 + 4.5f * r, 0));
  a.add(shapes::cone(7.2f, 12, 24), Vec3(0, 49, 0));
  return a.take();
}

Mesh tower3() {  // a glass box with a full window grid
  Assembly a;
  a.add(shapes::box({14, 48, 14}), Vec3(0));
  add_windows(a, 14, 14, 0, 4, 12, 3);
  a.add(shapes::box({6, 3, 6}), Vec3(0, 48, 0));
  return a.take();
}

Mesh tower4() {  // twin towers joined by sky bridges
  Assembly a;
  for (float side : {-1.0f, 1.0f}) {
    Assembly t;
    t.add(shapes::box({8, 40, 8}), Vec3(0));
    t.add(shapes::pyramid({8, 6, 8}), Vec3(0, 40, 0));
    add_windows(t, 8, 8, 0, 40.0f / 7, 7, 2);
    a.add(t.take(), Vec3(side * 6, 0, 0));
  }
  a.add(shapes::box({4, 3, 3}), Vec3(0, 18, 0));
  a.add(shapes::box({4, 3, 3}), Vec3(0, 30, 0));
  return a.take();
}

Mesh tower5() {  // a drum with a dome and an antenna
  Assembly a;
  a.add(shapes::box({20, 3, 20}), Vec3(0));
  a.add(shapes::cylinder(8, 36, 32), Vec3(0, 3, 0));
  for (int r = 1; r <= 4; ++r) a.add(shapes::cylinder(8.5f, 0.5f, 32), Vec3(0, 3 + 7.2f * r, 0));
  a.add(shapes::ellipsoid({8, 6, 8}, 32, 7), Vec3(0, 33, 0));
  a.add(shapes::cylinder(0.4f, 12, 8), Vec3(0, 44, 0));
  return a.take();
}

struct Design {
  const char* name;
  Mesh (*build)();
  float min_height_scale, max_height_scale;
  Rgba8 base_color;
};

constexpr Design kDesigns[] = {
    {"house1", house1, 0.9f, 1.1f, rgba8(196, 170, 140)},
    {"house2", house2, 0.9f, 1.2f, rgba8(210, 190, 160)},
    {"house3", house3, 0.9f, 1.2f, rgba8(220, 200, 170)},
    {"tower1", tower1, 0.7f, 1.6f, rgba8(150, 155, 165)},
    {"tower2", tower2, 0.7f, 1.6f, rgba8(170, 175, 185)},
    {"tower3", tower3, 0.7f, 1.6f, rgba8(120, 150, 180)},
    {"tower4", tower4, 0.7f, 1.4f, rgba8(160, 160, 150)},
    {"tower5", tower5, 0.7f, 1.4f, rgba8(185, 180, 175)},
};

// ---- Layout: streets, blocks and lots. ----------------------------------------------------

struct Street {
  double centre, width;
};

// Streets across one axis: street, block, street, …, street, covering at least `extent`.
// Blocks hold 2–5 lots of 10–30 m; streets are 10–30 m wide.
std::vector<Street> streets(double extent, Random rng) {
  std::vector<Street> lines;
  double x = 0.0;
  do {
    const double width = rng.uniform(10.0, 30.0);
    lines.push_back({x + width / 2, width});
    x += width + rng.uniform(40.0, 110.0);
  } while (x < extent);
  const double width = rng.uniform(10.0, 30.0);
  lines.push_back({x + width / 2, width});
  return lines;
}

struct Lots {
  double x0, z0, lot_w, lot_d;
  int nx, nz;
};

// Lots of the block between streets i, i+1 (x) and j, j+1 (z). Pitches come from the block's
// own stream so counting lots and generating them agree.
Lots block_lots(const std::vector<Street>& xs, const std::vector<Street>& zs, size_t i, size_t j,
                uint64_t seed) {
  Random rng = Random(seed).split(1 + j * xs.size() + i);
  const double x0 = xs[i].centre + xs[i].width / 2, x1 = xs[i + 1].centre - xs[i + 1].width / 2;
  const double z0 = zs[j].centre + zs[j].width / 2, z1 = zs[j + 1].centre - zs[j + 1].width / 2;
  const int nx = std::max(1, static_cast<int>((x1 - x0) / rng.uniform(10.0, 30.0)));
  const int nz = std::max(1, static_cast<int>((z1 - z0) / rng.uniform(10.0, 30.0)));
  return {x0, z0, (x1 - x0) / nx, (z1 - z0) / nz, nx, nz};
}

struct Layout {
  std::vector<Street> xs, zs;
  uint64_t lots = 0;
};

Layout layout(double extent, uint64_t seed) {
  Random rng(seed);
  Layout l{streets(extent, rng.split(0x57)), streets(extent, rng.split(0x5a)), 0};
  for (size_t j = 0; j + 1 < l.zs.size(); ++j)
    for (size_t i = 0; i + 1 < l.xs.size(); ++i) {
      const Lots b = block_lots(l.xs, l.zs, i, j, seed);
      l.lots += static_cast<uint64_t>(b.nx) * b.nz;
    }
  return l;
}

// A layout with at least `objects` lots. A derived extent starts from ~800 m² per object
// (a 75 m block of ~10 lots plus its share of street) and grows until the lots suffice.
Layout layout_for(const CityParams& p) {
  if (p.extent > 0.0) {
    Layout l = layout(p.extent, p.seed);
    if (l.lots < p.objects)
      fail("city", "extent " + std::to_string(p.extent) + " m holds only " +
                       std::to_string(l.lots) + " lots for " + std::to_string(p.objects) +
                       " objects; use a larger --extent or 0 to derive it");
    return l;
  }
  double extent = std::sqrt(static_cast<double>(p.objects) * 800.0);
  for (;;) {
    Layout l = layout(extent, p.seed);
    if (l.lots >= p.objects) return l;
    extent *= 1.02 * std::sqrt(static_cast<double>(p.objects) / std::max<uint64_t>(l.lots, 1));
  }
}

// Street centre lines at eye height: a grid graph, connected by construction.
NavGraph street_graph(const std::vector<Street>& xs, const std::vector<Street>& zs, double y) {
  NavGraph g;
  const auto node = [&](size_t i, size_t j) { return static_cast<uint32_t>(j * xs.size() + i); };
  for (size_t j = 0; j < zs.size(); ++j)
    for (size_t i = 0; i < xs.size(); ++i) {
      g.nodes.emplace_back(xs[i].centre, y, zs[j].centre);
      if (i > 0) g.edges.emplace_back(node(i - 1, j), node(i, j));
      if (j > 0) g.edges.emplace_back(node(i, j - 1), node(i, j));
    }
  return g;
}

// ---- Placing models on lots. -------------------------------------------------------------

// Scales, turns and moves `mesh` (standing on y = 0 around the Y axis) onto the lot centred at
// `centre`, shrinking it uniformly in plan until it clears the lot's setback.
void place_on_lot(Mesh& mesh, const Aabb& model_bounds, Vec3 scale, float yaw, Vec3 centre,
                  double lot_w, double lot_d) {
  Aabb turned = transformed(model_bounds, shapes::place(Vec3(0), yaw, scale));
  const double fit = std::min(
      {1.0, (lot_w - 2 * kSetback) / turned.size().x, (lot_d - 2 * kSetback) / turned.size().z});
  scale.x *= static_cast<float>(fit);
  scale.z *= static_cast<float>(fit);
  turned = transformed(model_bounds, shapes::place(Vec3(0), yaw, scale));
  const Vec3 shift(centre.x - turned.center().x, 0.0f, centre.z - turned.center().z);
  transform(mesh, shapes::place(shift, yaw, scale));
}

struct Model {
  Mesh mesh;
  Aabb bounds;
};

Model landmark_model(const CityParams& p) {
  const std::string file =
      p.landmark_mesh.empty() ? data_path("cgal/meshes/bunny00.off") : p.landmark_mesh;
  Mesh unit = shapes::unit_model(import_model(file).objects, file);
  const Aabb bounds = bounds_of(unit);
  return {std::move(unit), bounds};
}

Rgba8 vary(Rgba8 c, Random& rng) {
  const auto channel = [&](int shift) {
    const int v = static_cast<int>((c >> shift) & 0xff) + static_cast<int>(rng.integer(-25, 25));
    return static_cast<uint8_t>(std::clamp(v, 0, 255));
  };
  return rgba8(channel(0), channel(8), channel(16));
}

// Keeps `want` of the `total` items offered one by one, each equally likely (Knuth's selection
// sampling, TAOCP 3.4.2 Algorithm S): exact counts in one streaming pass.
class Selection {
 public:
  Selection(uint64_t want, uint64_t total, Random rng) : want_(want), left_(total), rng_(rng) {}
  bool take() {
    const bool taken = rng_.uniform() * static_cast<double>(left_) < static_cast<double>(want_);
    --left_;
    if (taken) --want_;
    return taken;
  }

 private:
  uint64_t want_, left_;
  Random rng_;
};

}  // namespace

SceneInfo generate_city(const CityParams& params, ObjectSink& sink) {
  if (!(params.landmark_fraction >= 0.0 && params.landmark_fraction <= 1.0))
    fail("city", "landmark fraction must be within [0, 1]");
  const Layout city = layout_for(params);
  SceneInfo info{"city", params.seed, {}, street_graph(city.xs, city.zs, kEyeHeight)};

  std::vector<Model> designs;
  for (const Design& d : kDesigns) {
    Mesh m = d.build();
    const Aabb b = bounds_of(m);
    designs.push_back({std::move(m), b});
  }
  const uint64_t landmarks =
      static_cast<uint64_t>(std::llround(params.landmark_fraction * params.objects));
  const Model landmark = landmarks > 0 ? landmark_model(params) : Model{};

  Random rng(params.seed);
  Selection lots(params.objects, city.lots, rng.split(0x107));
  Selection landmark_lots(landmarks, params.objects, rng.split(0x1a4d));
  shapes::ObjectEmitter out(sink, info);
  Mesh mesh;
  std::string name;
  for (size_t j = 0; j + 1 < city.zs.size(); ++j)
    for (size_t i = 0; i + 1 < city.xs.size(); ++i) {
      const Lots b = block_lots(city.xs, city.zs, i, j, params.seed);
      for (int lz = 0; lz < b.nz; ++lz)
        for (int lx = 0; lx < b.nx; ++lx) {
          if (!lots.take()) continue;
          Random r = rng.split(out.count());
          const Vec3 centre(static_cast<float>(b.x0 + (lx + 0.5) * b.lot_w), 0.0f,
                            static_cast<float>(b.z0 + (lz + 0.5) * b.lot_d));
          if (landmark_lots.take()) {
            // 3–20 m tall at any heading: the thesis's bunnies "with random transforms".
            mesh = landmark.mesh;
            const float size = static_cast<float>(r.uniform(3.0, 20.0));
            place_on_lot(mesh, landmark.bounds, Vec3(size),
                         static_cast<float>(r.uniform(0, 2 * kPi)), centre, b.lot_w, b.lot_d);
            name = "landmark/" + std::to_string(out.count());
            out.emit(name, vary(rgba8(200, 180, 150), r), mesh);
            continue;
          }
          const size_t d = static_cast<size_t>(r.integer(0, std::size(kDesigns) - 1));
          const Design& design = kDesigns[d];
          mesh = designs[d].mesh;
          const float plan = static_cast<float>(r.uniform(0.85, 1.15));
          const float height =
              static_cast<float>(r.uniform(design.min_height_scale, design.max_height_scale));
          // Quarter turns keep the buildings square to the streets.
          place_on_lot(mesh, designs[d].bounds, Vec3(plan, height, plan),
                       static_cast<float>(r.integer(0, 3)) * kPi / 2, centre, b.lot_w, b.lot_d);
          name = std::string(design.name) + "/" + std::to_string(out.count());
          out.emit(name, vary(design.base_color, r), mesh);
        }
    }
  return info;
}

}  // namespace cellwalk
