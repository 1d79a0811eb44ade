// vLOD paper (001) §5 Experiments: a stand-in for the UNC Powerplant (13 M triangles, small
// polygons and open areas that make occlusion "particularly tough"), which is not shipped.
// Process units on a grid separated by straight aisles — long sight lines, dense occluders —
// each with tanks, a boiler with drum and stack, pipe runs rising, bending and crossing with
// flanges and valves, grating walkways with railings, and ladders.
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/core/random.hpp"
#include "scene/shapes.hpp"

namespace cellwalk {
namespace {

using shapes::Assembly;

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kUnit = 36.0f;   // side of a process unit, metres
constexpr float kAisle = 12.0f;  // aisle width between units
constexpr float kPad = 0.3f;     // concrete pad under each unit
constexpr double kEyeHeight = 1.7;

const Rgba8 kSteel = rgba8(150, 155, 160), kRailing = rgba8(230, 190, 40),
            kGrating = rgba8(110, 110, 115);
const Rgba8 kServices[] = {rgba8(210, 200, 60), rgba8(60, 150, 80), rgba8(60, 100, 190),
                           rgba8(190, 60, 50), rgba8(200, 200, 200)};

// Rotation taking +Y to the axis-aligned or arbitrary unit direction `d`.
Mat4 turn_y_to(Vec3 d) {
  const Vec3 y(0, 1, 0);
  const float c = glm::dot(y, d);
  if (c > 0.9999f) return Mat4(1.0f);
  if (c < -0.9999f) return glm::rotate(Mat4(1.0f), kPi, Vec3(1, 0, 0));
  return glm::rotate(Mat4(1.0f), std::acos(c), glm::normalize(glm::cross(y, d)));
}

// Tessellation and counts scale with detail; never below what still reads as the part.
struct Detail {
  int sectors, bend_sectors, small_sectors;
  int pipe_runs, tanks;
  explicit Detail(double d)
      : sectors(std::max(8, int(std::lround(24 * d)))),
        bend_sectors(std::max(4, int(std::lround(8 * d)))),
        small_sectors(std::max(6, int(std::lround(12 * d)))),
        pipe_runs(std::max(2, int(std::lround(8 * d)))),
        tanks(std::max(1, int(std::lround(3 * d)))) {}
};

class UnitBuilder {
 public:
  UnitBuilder(shapes::ObjectEmitter& out, const Detail& detail, Vec3 origin, std::string prefix,
              Random rng)
      : out_(out), detail_(detail), origin_(origin), prefix_(std::move(prefix)), rng_(rng) {}

  void build() {
    emit("pad", rgba8(180, 175, 165), shapes::box({kUnit, kPad, kUnit}), {kUnit / 2, 0, kUnit / 2});
    for (int t = 0; t < detail_.tanks; ++t) tank(t);
    boiler();
    for (int p = 0; p < detail_.pipe_runs; ++p) pipe_run(p);
    walkway(0, 4.0f);
    walkway(1, 8.0f);
  }

 private:
  void emit(const std::string& what, Rgba8 c, Mesh m, Vec3 local) {
    transform(m, Assembly::translate(origin_ + local));
    out_.emit(prefix_ + what, c, m);
  }

  // Tanks in a row along the unit's south edge, each with a dome and a ladder up its side.
  void tank(int t) {
    const float slot = (kUnit - 4) / float(detail_.tanks);
    const float r = std::min(slot * 0.4f, float(rng_.uniform(2.0, 4.0)));
    const float h = float(rng_.uniform(6.0, 14.0));
    const Vec3 at(2 + slot * (t + 0.5f), kPad, 2 + 4.0f);
    Assembly a;
    a.add(shapes::cylinder(r, h, detail_.sectors), Vec3(0));
    a.add(shapes::ellipsoid({r, r * 0.35f, r}, detail_.sectors, std::max(3, detail_.sectors / 4)),
          Vec3(0, h - r * 0.35f, 0));
    const std::string id = "tank" + std::to_string(t);
    emit(id, rgba8(225, 225, 220), a.take(), at);
    emit(id + "/ladder", kRailing, ladder(h), at + Vec3(0, 0, -r - 0.1f));
  }

  // Two rails and a rung every 0.3 m, running from y = 0 up to `height`, in the XY plane.
  static Mesh ladder(float height) {
    Assembly a;
    for (float x : {-0.25f, 0.25f}) a.add(shapes::box({0.05f, height, 0.05f}), Vec3(x, 0, 0));
    for (float y = 0.3f; y < height; y += 0.3f)
      a.add(shapes::box({0.5f, 0.03f, 0.03f}), Vec3(0, y, 0));
    return a.take();
  }

  void boiler() {
    const Vec3 at(kUnit - 9, kPad, kUnit - 10);
    const Rgba8 brick = rgba8(150, 70, 55);
    emit("boiler", brick, shapes::box({10, 14, 8}), at);
    Mesh drum = shapes::cylinder(1.5f, 9, detail_.sectors);
    transform(drum,
              glm::rotate(Mat4(1.0f), kPi / 2, Vec3(0, 0, 1)) * Assembly::translate({0, -4.5f, 0}));
    emit("boiler/drum", kSteel, std::move(drum), at + Vec3(0, 15.5f, 0));
    emit("boiler/stack", rgba8(90, 90, 95), shapes::cylinder(1.0f, 30, detail_.sectors),
         at + Vec3(3, 14, 2));
  }

  // Up from the pad, a bend, across the unit, a bend, back down: with flanges at the joints
  // and a valve on the rising leg. Runs alternate between crossing along X and along Z.
  void pipe_run(int p) {
    const float r = float(rng_.uniform(0.1, 0.35)), bend = r * 3;
    const float top = float(rng_.uniform(3.0, 9.0));
    const bool along_x = p % 2 == 0;
    const float lane =
        12 + (kUnit - 16) * (float(p / 2) + 0.5f) / float((detail_.pipe_runs + 1) / 2);
    const float span = float(rng_.uniform(10.0, kUnit - 8));
    const Vec3 dir = along_x ? Vec3(1, 0, 0) : Vec3(0, 0, 1);
    const Vec3 start = along_x ? Vec3(3, kPad, lane) : Vec3(lane, kPad, 3);
    const Vec3 end = start + dir * span;
    const float yaw = along_x ? 0.0f : -kPi / 2;
    const int n = detail_.small_sectors;
    Assembly a;
    a.add(pipe(r, top - kPad, n), Vec3(0));
    a.add(elbow(r, bend, yaw), Vec3(0, top - kPad, 0));
    a.add(pipe(r, span - 2 * bend, n),
          Assembly::translate(dir * bend + Vec3(0, top - kPad + bend, 0)) * turn_y_to(dir));
    a.add(elbow(r, bend, yaw + kPi), dir * span + Vec3(0, top - kPad, 0));
    a.add(pipe(r, top - kPad, n), dir * span);
    const Rgba8 service = kServices[rng_.integer(0, std::size(kServices) - 1)];
    const std::string id = "pipe" + std::to_string(p);
    emit(id, service, a.take(), start);
    for (float y : {1.0f, top - 1.5f}) {
      const std::string at = std::to_string(int(y * 10));
      emit(id + "/flange" + at, kSteel, flange(r, Vec3(0, 1, 0)), start + Vec3(0, y, 0));
      emit(id + "/flange" + at + "b", kSteel, flange(r, Vec3(0, 1, 0)), end + Vec3(0, y, 0));
    }
    emit(id + "/flange_mid", kSteel, flange(r, dir),
         start + dir * (span / 2) + Vec3(0, top + bend - kPad, 0));
    emit(id + "/valve", rgba8(200, 40, 40), valve(r, dir), start + Vec3(0, 1.6f, 0));
  }

  // A bend from a pipe rising along +Y to one running along the direction `yaw` turns +X to.
  Mesh elbow(float r, float bend, float yaw) const {
    Mesh m = shapes::torus(bend, r, detail_.bend_sectors, detail_.small_sectors, kPi / 2);
    transform(m, glm::rotate(Mat4(1.0f), yaw, Vec3(0, 1, 0)) * Assembly::translate({bend, 0, 0}) *
                     glm::rotate(Mat4(1.0f), kPi, Vec3(0, 0, 1)) *
                     glm::rotate(Mat4(1.0f), kPi / 2, Vec3(1, 0, 0)));
    return m;
  }

  static Mesh pipe(float r, float length, int n) { return shapes::cylinder(r, length, n, false); }

  // A collar around a pipe along `axis`, ringed by eight bolt heads.
  Mesh flange(float r, Vec3 axis) const {
    Assembly a;
    a.add(shapes::cylinder(r * 1.7f, 0.08f, detail_.small_sectors), Vec3(0, -0.04f, 0));
    for (int b = 0; b < 8; ++b) {
      const float angle = 2 * kPi * float(b) / 8;
      a.add(shapes::box({0.05f, 0.12f, 0.05f}),
            Vec3(r * 1.45f * std::cos(angle), -0.06f, r * 1.45f * std::sin(angle)));
    }
    Mesh m = a.take();
    transform(m, turn_y_to(axis));
    return m;
  }

  // A valve body on the pipe with a stem and hand wheel standing off to one side.
  Mesh valve(float r, Vec3 side) const {
    Assembly a;
    a.add(shapes::cylinder(r * 1.4f, 0.5f, detail_.small_sectors), Vec3(0, -0.25f, 0));
    const Mat4 out = turn_y_to(side);
    a.add(shapes::cylinder(0.03f, r * 1.4f + 0.3f, 6), out);
    a.add(shapes::torus(0.2f, 0.02f, detail_.small_sectors, 6),
          out * Assembly::translate({0, r * 1.4f + 0.3f, 0}));
    return a.take();
  }

  // A grating slab along the north (0) or east (1) edge at `height`, railed on its outer side,
  // on columns, with a ladder at one end.
  void walkway(int side, float height) {
    const float length = kUnit - 6, width = 1.2f;
    Assembly a;
    a.add(shapes::box({length, 0.05f, width}), Vec3(0, height, 0));
    for (float x = -length / 2; x <= length / 2 + 0.01f; x += 1.5f)
      a.add(shapes::box({0.05f, 1.1f, 0.05f}), Vec3(x, height, width / 2));
    for (float y : {0.55f, 1.05f})
      a.add(shapes::box({length, 0.05f, 0.05f}), Vec3(0, height + y, width / 2));
    for (float x = -length / 2; x <= length / 2 + 0.01f; x += 6.0f)
      a.add(shapes::box({0.2f, height, 0.2f}), Vec3(x, 0, 0));
    Mesh m = a.take();
    Mesh steps = ladder(height);
    transform(steps, Assembly::translate({-length / 2 - 0.4f, 0, 0}) *
                         glm::rotate(Mat4(1.0f), kPi / 2, Vec3(0, 1, 0)));
    const Mat4 to_edge = side == 0 ? Assembly::translate({kUnit / 2, 0, kUnit - 2})
                                   : Assembly::translate({kUnit - 2, 0, kUnit / 2}) *
                                         glm::rotate(Mat4(1.0f), kPi / 2, Vec3(0, 1, 0));
    transform(m, to_edge);
    transform(steps, to_edge);
    const std::string id = "walkway" + std::to_string(side);
    emit(id, kGrating, std::move(m), Vec3(0, kPad, 0));
    emit(id + "/ladder", kRailing, std::move(steps), Vec3(0, kPad, 0));
  }

  shapes::ObjectEmitter& out_;
  const Detail& detail_;
  Vec3 origin_;
  std::string prefix_;
  Random rng_;
};

// Aisle centre lines at eye height: a grid graph around and between the units.
NavGraph aisle_graph(int ux, int uz) {
  NavGraph g;
  const float pitch = kUnit + kAisle, y = static_cast<float>(kEyeHeight);
  const auto node = [&](int i, int j) { return static_cast<uint32_t>(j * (ux + 1) + i); };
  for (int j = 0; j <= uz; ++j)
    for (int i = 0; i <= ux; ++i) {
      g.nodes.emplace_back(kAisle / 2 + i * pitch, y, kAisle / 2 + j * pitch);
      if (i > 0) g.edges.emplace_back(node(i - 1, j), node(i, j));
      if (j > 0) g.edges.emplace_back(node(i, j - 1), node(i, j));
    }
  return g;
}

}  // namespace

SceneInfo generate_plant(const PlantParams& params, ObjectSink& sink) {
  if (params.units_x < 1 || params.units_z < 1) fail("plant", "needs at least one unit each way");
  if (!(params.detail > 0.0 && params.detail <= 16.0))
    fail("plant", "detail must be within (0, 16]");
  SceneInfo info{"plant", params.seed, {}, aisle_graph(params.units_x, params.units_z)};
  shapes::ObjectEmitter out(sink, info);
  const Detail detail(params.detail);
  Random rng(params.seed);
  for (int j = 0; j < params.units_z; ++j)
    for (int i = 0; i < params.units_x; ++i) {
      const Vec3 origin(kAisle + i * (kUnit + kAisle), 0, kAisle + j * (kUnit + kAisle));
      const std::string prefix = "plant/u" + std::to_string(i) + "_" + std::to_string(j) + "/";
      UnitBuilder(out, detail, origin, prefix, rng.split(1 + uint64_t(j) * params.units_x + i))
          .build();
    }
  return info;
}

}  // namespace cellwalk
