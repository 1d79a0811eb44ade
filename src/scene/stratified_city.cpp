// Stratified rendering thesis (002), Appendix A "Random City Model Generator" and §A.1: a grid
// of blocks between streets with curbs; park blocks (one park, central fountain) and building
// blocks cut into random rows, then random columns; each slot empty, a park of four L-shaped
// grass strips, a fountain of stacked layers, or a building (cylindrical or rectangular, solid
// or semi-transparent, cone or pyramid top, segments of one or alternating colours, optional
// floor dividers); some blocks lined with trees.
#include <cmath>
#include <string>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/core/random.hpp"
#include "scene/shapes.hpp"

namespace cellwalk {
namespace {

using shapes::Assembly;

constexpr double kEyeHeight = 1.7;
constexpr double kParkBlockChance = 0.15;  // [ours] Appendix A gives no proportions
constexpr double kTreeLinedChance = 0.4;
constexpr double kMinSlot = 5.0;  // slots narrower than this stay empty ("too small")
constexpr double kAlley = 1.0;    // half the gap between neighbouring slots
constexpr float kFloorHeight = 3.5f;

const Rgba8 kGrass = rgba8(70, 150, 60), kWater = rgba8(70, 130, 220),
            kStone = rgba8(170, 165, 155);

struct Rect {
  double x0, z0, x1, z1;
  double w() const { return x1 - x0; }
  double d() const { return z1 - z0; }
  Vec3 centre() const { return Vec3(float((x0 + x1) / 2), 0.0f, float((z0 + z1) / 2)); }
  Rect inset(double m) const { return {x0 + m, z0 + m, x1 - m, z1 - m}; }
};

Mesh painted(Mesh m, Rgba8 c) {
  shapes::paint(m, c);
  return m;
}

// An axis-aligned slab from `r` between heights y0 and y1.
void add_slab(Assembly& a, const Rect& r, double y0, double y1, Rgba8 c) {
  a.add(painted(shapes::box(Vec3(float(r.w()), float(y1 - y0), float(r.d()))), c),
        r.centre() + Vec3(0, float(y0), 0));
}

// Four L-shaped grass strips, one in each corner of `r`.
Mesh park(const Rect& r) {
  Assembly a;
  const double strip = std::min(r.w(), r.d()) * 0.15, arm_x = r.w() * 0.4, arm_z = r.d() * 0.4;
  for (int corner = 0; corner < 4; ++corner) {
    const bool east = corner & 1, north = corner & 2;
    const double x = east ? r.x1 - arm_x : r.x0, z = north ? r.z1 - strip : r.z0;
    add_slab(a, {x, z, x + arm_x, z + strip}, 0, 0.05, kGrass);
    const double xs = east ? r.x1 - strip : r.x0, zs = north ? r.z1 - arm_z : r.z0 + strip;
    add_slab(a, {xs, zs, xs + strip, zs + arm_z - strip}, 0, 0.05, kGrass);
  }
  return a.take();
}

// Layers of wall and water; each inner layer smaller and taller than the one outside it.
Mesh fountain(Vec3 centre, double radius, Random& rng) {
  Assembly a;
  const int layers = static_cast<int>(rng.integer(2, 4));
  const float step = static_cast<float>(rng.uniform(0.4, 1.0));
  for (int i = 0; i < layers; ++i) {
    const float r = static_cast<float>(radius) * (1.0f - float(i) / float(layers + 1));
    const float h = step * float(i + 1);
    a.add(painted(shapes::cylinder(r, h, 24), kStone), centre);
    a.add(painted(shapes::cylinder(r * 0.85f, 0.05f, 24), kWater), centre + Vec3(0, h, 0));
  }
  return a.take();
}

Rgba8 random_colour(Random& rng, uint8_t alpha) {
  return rgba8(uint8_t(rng.integer(60, 230)), uint8_t(rng.integer(60, 230)),
               uint8_t(rng.integer(60, 230)), alpha);
}

struct BuildingStyle {
  bool round, cone_top;
  uint8_t alpha;  // 255 solid; below, semi-transparent
};

// One segment of a building: a prism from y0 to y1, one colour or floors in two alternating
// colours, with thin dividers at the floors when asked.
void add_segment(Assembly& a, const BuildingStyle& s, Vec3 centre, Vec2 size, float y0, float y1,
                 Random& rng) {
  const Rgba8 c0 = random_colour(rng, s.alpha), c1 = random_colour(rng, s.alpha);
  const bool alternating = rng.chance(0.5), dividers = rng.chance(0.5);
  const int floors = std::max(1, static_cast<int>(std::lround((y1 - y0) / kFloorHeight)));
  const float floor_h = (y1 - y0) / float(floors);
  const auto prism = [&](Vec2 plan, float height) {
    if (!s.round) return shapes::box(Vec3(plan.x, height, plan.y));
    Mesh m = shapes::cylinder(0.5f, height, 20);
    transform(m, shapes::place(Vec3(0), 0, Vec3(plan.x, 1, plan.y)));
    return m;
  };
  if (alternating) {
    for (int f = 0; f < floors; ++f)
      a.add(painted(prism(size, floor_h), f % 2 ? c1 : c0), centre + Vec3(0, y0 + floor_h * f, 0));
  } else {
    a.add(painted(prism(size, y1 - y0), c0), centre + Vec3(0, y0, 0));
  }
  if (!dividers) return;
  for (int f = 1; f < floors; ++f)
    a.add(painted(prism(size * 1.04f, 0.2f), c1), centre + Vec3(0, y0 + floor_h * f - 0.1f, 0));
}

Mesh building(const Rect& slot, double max_height, Random& rng, Rgba8& colour) {
  const BuildingStyle style{rng.chance(0.4), rng.chance(0.5),
                            uint8_t(rng.chance(0.25) ? 140 : 255)};
  const float height = static_cast<float>(rng.uniform(0.15, 0.85) * max_height);
  const float top =
      static_cast<float>(std::min(rng.uniform(0.05, 0.15) * max_height, max_height - height));
  Vec2 plan(float(slot.w()), float(slot.d()));
  const int segments = static_cast<int>(rng.integer(1, 4));
  Assembly a;
  float y = 0;
  for (int s = 0; s < segments; ++s) {
    const float y1 = height * float(s + 1) / float(segments);
    add_segment(a, style, slot.centre(), plan, y, y1, rng);
    y = y1;
    plan *= static_cast<float>(rng.uniform(0.7, 0.95));  // each segment set back from the one below
  }
  Mesh roof = style.cone_top ? shapes::cone(0.5f, 1.0f, 20) : shapes::pyramid(Vec3(1));
  transform(roof, shapes::place(slot.centre() + Vec3(0, y, 0), 0, Vec3(plan.x, top, plan.y)));
  colour = random_colour(rng, style.alpha);
  a.add(painted(std::move(roof), colour), Mat4(1.0f));
  return a.take();
}

Mesh tree(Vec3 at, Random& rng) {
  Assembly a;
  const float h = static_cast<float>(rng.uniform(4.0, 8.0));
  a.add(painted(shapes::cylinder(0.15f, h * 0.4f, 6), rgba8(110, 80, 50)), at);
  Mesh crown = rng.chance(0.5) ? shapes::cone(h * 0.22f, h * 0.7f, 10)
                               : shapes::ellipsoid(Vec3(h * 0.22f, h * 0.35f, h * 0.22f), 10, 6);
  a.add(painted(std::move(crown), rgba8(40, uint8_t(rng.integer(110, 160)), 40)),
        at + Vec3(0, h * 0.3f, 0));
  return a.take();
}

// Random cut positions dividing [lo, hi] into between 1 and `max_parts` parts.
std::vector<double> cuts(double lo, double hi, int max_parts, Random& rng) {
  const int parts = static_cast<int>(rng.integer(1, std::max(1, max_parts)));
  std::vector<double> weights(parts);
  double total = 0;
  for (double& w : weights) total += (w = rng.uniform(0.5, 1.5));
  std::vector<double> at{lo};
  for (double w : weights) at.push_back(at.back() + (hi - lo) * w / total);
  at.back() = hi;
  return at;
}

class Generator {
 public:
  Generator(const StratifiedCityParams& p, ObjectSink& sink)
      : p_(p), info_{"stratified-city", p.seed, {}, {}}, out_(sink, info_), rng_(p.seed) {}

  SceneInfo run() {
    streets();
    for (int j = 0; j < p_.blocks_z; ++j)
      for (int i = 0; i < p_.blocks_x; ++i) block(i, j);
    nav();
    return std::move(info_);
  }

 private:
  double pitch_x() const { return p_.block_length + p_.street_width; }
  double pitch_z() const { return p_.block_width + p_.street_width; }

  void emit(const std::string& name, Rgba8 c, Mesh m) { out_.emit(name, c, m); }

  // Streets along X span the city one block at a time, intersections included; streets along
  // Z fill the gaps between them, so no two street slabs overlap.
  void streets() {
    const Rgba8 asphalt = rgba8(60, 60, 65);
    const double sw = p_.street_width, h = p_.street_height;
    for (int j = 0; j <= p_.blocks_z; ++j)
      for (int i = 0; i < p_.blocks_x; ++i) {
        const double x1 = (i + 1) * pitch_x() + (i + 1 == p_.blocks_x ? sw : 0.0);
        Assembly a;
        add_slab(a, {i * pitch_x(), j * pitch_z(), x1, j * pitch_z() + sw}, 0, h, asphalt);
        emit("street/x" + std::to_string(j) + "_" + std::to_string(i), asphalt, a.take());
      }
    for (int i = 0; i <= p_.blocks_x; ++i)
      for (int j = 0; j < p_.blocks_z; ++j) {
        Assembly a;
        add_slab(a, {i * pitch_x(), j * pitch_z() + sw, i * pitch_x() + sw, (j + 1) * pitch_z()}, 0,
                 h, asphalt);
        emit("street/z" + std::to_string(i) + "_" + std::to_string(j), asphalt, a.take());
      }
  }

  void block(int i, int j) {
    Random rng = rng_.split(1 + uint64_t(j) * p_.blocks_x + i);
    const std::string id = std::to_string(i) + "_" + std::to_string(j);
    const Rect r{i * pitch_x() + p_.street_width, j * pitch_z() + p_.street_width,
                 (i + 1) * pitch_x(), (j + 1) * pitch_z()};
    curb(r, id);
    Rect inner = r.inset(p_.curb_width);
    if (rng.chance(kTreeLinedChance) && p_.tree_spacing > 0) {
      trees(inner.inset(1.0), id, rng);
      inner = inner.inset(2.5);
    }
    if (inner.w() < kMinSlot || inner.d() < kMinSlot) return;
    if (rng.chance(kParkBlockChance)) {
      emit("park/" + id, kGrass, park(inner));
      emit("fountain/" + id, kStone,
           fountain(inner.centre(), std::min(inner.w(), inner.d()) * 0.15, rng));
      return;
    }
    const std::vector<double> rows = cuts(inner.z0, inner.z1, p_.rows_per_block, rng);
    for (size_t row = 0; row + 1 < rows.size(); ++row) {
      const std::vector<double> cols = cuts(inner.x0, inner.x1, p_.columns_per_block, rng);
      for (size_t col = 0; col + 1 < cols.size(); ++col)
        slot(Rect{cols[col], rows[row], cols[col + 1], rows[row + 1]}.inset(kAlley),
             id + "_" + std::to_string(row) + "_" + std::to_string(col), rng);
    }
  }

  void slot(const Rect& s, const std::string& id, Random& rng) {
    if (s.w() < kMinSlot || s.d() < kMinSlot) return;
    const double pick = rng.uniform();
    if (pick < 0.1) return emit("park/" + id, kGrass, park(s));
    if (pick < 0.2)
      return emit("fountain/" + id, kStone,
                  fountain(s.centre(), std::min(s.w(), s.d()) * 0.4, rng));
    Rgba8 colour;
    Mesh m = building(s, p_.max_height, rng, colour);
    emit("building/" + id, colour, std::move(m));
  }

  // A raised ring of curb_width around the block.
  void curb(const Rect& r, const std::string& id) {
    const double c = p_.curb_width, h = p_.curb_height;
    Assembly a;
    add_slab(a, {r.x0, r.z0, r.x1, r.z0 + c}, 0, h, kStone);
    add_slab(a, {r.x0, r.z1 - c, r.x1, r.z1}, 0, h, kStone);
    add_slab(a, {r.x0, r.z0 + c, r.x0 + c, r.z1 - c}, 0, h, kStone);
    add_slab(a, {r.x1 - c, r.z0 + c, r.x1, r.z1 - c}, 0, h, kStone);
    emit("curb/" + id, kStone, a.take());
  }

  // Trees every tree_spacing metres round the loop `line`, corners once.
  void trees(const Rect& line, const std::string& id, Random& rng) {
    const Vec3 corners[] = {{float(line.x0), 0, float(line.z0)},
                            {float(line.x1), 0, float(line.z0)},
                            {float(line.x1), 0, float(line.z1)},
                            {float(line.x0), 0, float(line.z1)}};
    int n = 0;
    for (int side = 0; side < 4; ++side) {
      const Vec3 from = corners[side], to = corners[(side + 1) % 4];
      const int count = std::max(1, static_cast<int>(glm::length(to - from) / p_.tree_spacing));
      for (int k = 0; k < count; ++k)
        emit("tree/" + id + "_" + std::to_string(n++), rgba8(40, 130, 40),
             tree(from + (to - from) * (float(k) / float(count)), rng));
    }
  }

  // Street centre lines at eye height above the street surface.
  void nav() {
    const float y = static_cast<float>(p_.street_height + kEyeHeight);
    const auto node = [&](int i, int j) {
      return static_cast<uint32_t>(j * (p_.blocks_x + 1) + i);
    };
    for (int j = 0; j <= p_.blocks_z; ++j)
      for (int i = 0; i <= p_.blocks_x; ++i) {
        info_.nav.nodes.emplace_back(float(i * pitch_x() + p_.street_width / 2), y,
                                     float(j * pitch_z() + p_.street_width / 2));
        if (i > 0) info_.nav.edges.emplace_back(node(i - 1, j), node(i, j));
        if (j > 0) info_.nav.edges.emplace_back(node(i, j - 1), node(i, j));
      }
  }

  const StratifiedCityParams& p_;
  SceneInfo info_;
  shapes::ObjectEmitter out_;
  Random rng_;
};

void check(const StratifiedCityParams& p) {
  if (p.blocks_x < 1 || p.blocks_z < 1)
    fail("stratified-city", "needs at least one block each way");
  if (!(p.block_length > 0 && p.block_width > 0 && p.street_width > 0 && p.max_height > 0))
    fail("stratified-city", "block sizes, street width and maximum height must be positive");
  if (p.rows_per_block < 1 || p.columns_per_block < 1)
    fail("stratified-city", "rows and columns per block must be at least 1");
  if (2 * p.curb_width >= std::min(p.block_length, p.block_width))
    fail("stratified-city", "the curbs are wider than the block");
}

}  // namespace

SceneInfo generate_stratified_city(const StratifiedCityParams& params, ObjectSink& sink) {
  check(params);
  return Generator(params, sink).run();
}

}  // namespace cellwalk
