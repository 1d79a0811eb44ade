// The path planner (cellwalk/precompute/path_planner.hpp): every frame of every session kind on
// a planned graph keeps the clearance from every triangle of the world, checked by brute force
// with a distance of the test's own; the paths move through the space; the doorway of a room
// is found; a model is in view; no free space is one clear error; the same seed gives the same
// graph and path.
#include "cellwalk/precompute/path_planner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <tuple>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/scene/path_generator.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/render/renderer.hpp"
#include "precompute/embree_scene.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using glm::dvec3;

const char* const kKinds[] = {"normal", "slow", "fast", "turning", "backward", "back-and-forth", "random"};

// Every level-0 triangle of the world, three corners each.
std::vector<dvec3> all_triangles(const World& world) {
  std::vector<dvec3> corners;
  for (ObjectId id = 0; id < world.object_count(); ++id) {
    const Mesh mesh = world.decode_level(id, 0, world.read_level(id, 0));
    for (uint32_t i : mesh.indices) corners.emplace_back(mesh.positions[i]);
  }
  return corners;
}

double point_segment(const dvec3& p, const dvec3& a, const dvec3& b) {
  const double len2 = glm::dot(b - a, b - a);
  const double t = len2 > 0 ? std::clamp(glm::dot(p - a, b - a) / len2, 0.0, 1.0) : 0.0;
  return glm::length(p - (a + t * (b - a)));
}

// The oracle: the distance from p to the nearest triangle, brute force over all of them, by a
// route other than the planner's: the foot of the perpendicular when it falls inside the
// triangle, else the nearest of its edges.
double oracle_distance(const std::vector<dvec3>& corners, const dvec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < corners.size(); i += 3) {
    const dvec3 &a = corners[i], &b = corners[i + 1], &c = corners[i + 2];
    const dvec3 n = glm::cross(b - a, c - a);
    const double n2 = glm::dot(n, n);
    if (n2 > 0) {
      const dvec3 foot = p - n * (glm::dot(p - a, n) / n2);
      if (glm::dot(glm::cross(b - a, foot - a), n) >= 0 && glm::dot(glm::cross(c - b, foot - b), n) >= 0 &&
          glm::dot(glm::cross(a - c, foot - c), n) >= 0) {
        best = std::min(best, glm::length(p - foot));
        continue;
      }
    }
    best = std::min({best, point_segment(p, a, b), point_segment(p, b, c), point_segment(p, c, a)});
  }
  return best;
}

struct Checked {
  double min_distance = std::numeric_limits<double>::infinity();
  size_t cells = 0;  // distinct grid cells the normal path visits
};

// Every frame of a path of each kind keeps the clearance (less the float rounding of a frame's
// position between two nodes); returns the least distance found and the normal path's cells.
Checked check_every_kind(const World& world, const PlannedSpace& space, int frames) {
  const std::vector<dvec3> corners = all_triangles(world);
  const double clearance = space.options.clearance;
  Checked out;
  for (const char* kind : kKinds) {
    PathParams p;
    p.kind = parse_session_kind(kind);
    p.frames = frames;
    p.seed = 3;
    const CameraPath path = generate_path(space.nav, p);
    std::set<std::tuple<int, int, int>> cells;
    for (size_t i = 0; i < path.frames.size(); ++i) {
      const Vec3 e = path.frames[i].position;
      const double d = oracle_distance(corners, dvec3(e));
      const double rounding = 1e-5 * (1.0 + glm::length(dvec3(e)));
      EXPECT_GE(d, clearance - rounding) << kind << " frame " << i << " at (" << e.x << ", " << e.y << ", " << e.z << ")";
      out.min_distance = std::min(out.min_distance, d);
      const auto cell = [&](float v) { return static_cast<int>(std::floor(v / space.options.spacing)); };
      cells.insert({cell(e.x), cell(e.y), cell(e.z)});
    }
    if (std::string(kind) == "normal") out.cells = cells.size();
  }
  return out;
}

void report(const char* name, const World& world, const PlannedSpace& s, const Checked& c) {
  std::printf("%s: %llu triangles; %zu nodes, %zu edges (of %llu points, %llu free, %llu components); "
              "%.2f s + %.2f s loading; clearance %.3g, least distance found %.4g; normal path visits %zu cells\n",
              name, static_cast<unsigned long long>(world.triangle_count()), s.nav.nodes.size(), s.nav.edges.size(),
              static_cast<unsigned long long>(s.candidates), static_cast<unsigned long long>(s.free),
              static_cast<unsigned long long>(s.components), s.plan_seconds, s.load_seconds, s.options.clearance,
              c.min_distance, c.cells);
}

// The Stanford bunny standing on a 6 × 6 m ground quad (its lowest point at y = 0).
std::string bunny_on_ground(const test::TempDir& dir) {
  std::vector<Object> objects = import_model(test::cgal_mesh("bunny00.off")).objects;
  Aabb box;
  for (const Object& o : objects) box.extend(o.bounds);
  const Vec3 shift(-box.center().x, -box.min.y, -box.center().z);
  for (Object& o : objects)
    for (Vec3& v : o.mesh.positions) v += shift;
  Object ground;
  ground.id = static_cast<ObjectId>(objects.size());
  ground.name = "ground";
  ground.mesh = test::quad_mesh({-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3});
  objects.push_back(ground);
  return test::write_world(dir, objects, {}, "bunny");
}

std::string room_world(const test::TempDir& dir) {
  Object room;
  room.name = "room";
  room.mesh = test::double_sided_room_with_door();
  return test::write_world(dir, {room}, {}, "room");
}

TEST(PathPlanner, GeneratedCityEveryKindKeepsTheClearance) {
  test::TempDir dir;
  {
    SceneWriter writer(dir.file("c.cwscene"));
    CityParams city;
    city.objects = 40;
    city.landmark_fraction = 0;  // a bunny's 70k triangles would make the oracle slow
    city.seed = 7;
    writer.finish(generate_city(city, writer));
  }
  build_world(dir.file("c.cwscene"), dir.file("c.cww"), BuildParams{});
  const World world(dir.file("c.cww"));
  const PlannedSpace space = plan_free_space(world);
  EXPECT_NEAR(space.options.eye_height, 1.7, 1e-9);
  EXPECT_NEAR(space.options.clearance, 0.3, 1e-9);
  const Checked c = check_every_kind(world, space, 300);
  report("city", world, space, c);
  EXPECT_GE(c.cells, 8u);
}

TEST(PathPlanner, BunnyOnAGroundEveryKindKeepsTheClearanceAndSeesTheBunny) {
  test::TempDir dir;
  const World world(bunny_on_ground(dir));
  const PlannedSpace space = plan_free_space(world);
  const Checked c = check_every_kind(world, space, 300);
  report("bunny", world, space, c);
  EXPECT_GE(c.cells, 10u);

  // In view: some ray through a 32 × 24 grid of the image hits the bunny (object 0) first.
  // Measured: 28 % of all kinds' frames (normal 34 %, fast 7 %, random 59 %), against 9 % on
  // the import's loop (issue 16); the session kinds look along their travel, so "most frames"
  // needs a view that looks at the model, which they do not have (docs/path-planner.md).
  const visibility::EmbreeScene scene(world);
  int seen_all = 0, frames_all = 0;
  for (const char* kind : kKinds) {
    PathParams p;
    p.kind = parse_session_kind(kind);
    p.frames = 300;
    p.seed = 3;
    const CameraPath path = generate_path(space.nav, p);
    int seen = 0;
    for (const PathFrame& f : path.frames) {
      Camera camera;
      apply(f, camera);
      const float ty = std::tan(glm::radians(camera.fov_y_deg / 2)), tx = ty * camera.aspect;
      bool hit = false;
      for (int y = 0; y < 24 && !hit; ++y)
        for (int x = 0; x < 32 && !hit; ++x) {
          const float u = (x + 0.5f) / 32 * 2 - 1, v = (y + 0.5f) / 24 * 2 - 1;
          const Vec3 dir = glm::normalize(camera.forward() + camera.right() * (u * tx) + camera.up() * (v * ty));
          const auto id = scene.first_hit(camera.position, dir, camera.far_plane);
          hit = id && *id == 0;
        }
      seen += hit;
    }
    std::printf("bunny in view: %s %d of %zu frames\n", kind, seen, path.frames.size());
    EXPECT_GT(seen, 0) << kind;
    seen_all += seen;
    frames_all += static_cast<int>(path.frames.size());
  }
  EXPECT_GE(5 * seen_all, frames_all);  // at least 20 %
}

// The share of each frame showing the world by rays (view_coverage) against the share of
// pixels with an object id in the rendered image, on the inspection path around the bunny:
// the model is in view in every frame, and the two measures agree to the ray grid's resolution.
TEST(PathPlanner, ViewCoverageAgreesWithTheRenderedImage) {
  test::TempDir dir;
  std::vector<Object> bunny = import_model(test::cgal_mesh("bunny00.off")).objects;
  const World world(test::write_world(dir, bunny, {}, "bunny_alone"));
  PathParams p;
  p.frames = 12;
  const CameraPath path = inspection_path(world.info().bounds, p);
  Camera lens;
  lens.aspect = 4.0f / 3.0f;
  const std::vector<float> rays = view_coverage(world, path, lens, 128);
  ASSERT_EQ(rays.size(), path.frames.size());
  auto context = GlContext::headless();
  RenderSettings settings;
  settings.width = 256;
  settings.height = 192;
  Renderer renderer(settings);
  auto brute = make_strategy("brute", world, {});
  for (size_t i = 0; i < path.frames.size(); ++i) {
    Camera cam = lens;
    apply(path.frames[i], cam);
    render_frame(*brute, renderer, cam);
    const IdImage ids = renderer.read_ids();
    const double drawn = double(std::count_if(ids.ids.begin(), ids.ids.end(), [](uint32_t id) { return id != kBackgroundId; })) / ids.ids.size();
    EXPECT_GT(drawn, 0.05) << "frame " << i;
    EXPECT_NEAR(rays[i], drawn, 0.01) << "frame " << i;
  }
}

TEST(PathPlanner, RoomWithADoorwayEveryKindKeepsTheClearanceAndTheGraphGoesInside) {
  test::TempDir dir;
  const World world(room_world(dir));
  const PlannedSpace space = plan_free_space(world);
  const Checked c = check_every_kind(world, space, 300);
  report("room", world, space, c);
  // The largest component holds nodes inside the room and outside it: it passes the doorway.
  size_t inside = 0, outside = 0;
  for (const Vec3& n : space.nav.nodes) {
    const bool in = n.x > 0 && n.x < 10 && n.z > 0 && n.z < 10 && n.y < 3;
    inside += in;
    outside += !in;
  }
  EXPECT_GT(inside, 100u);
  EXPECT_GT(outside, 100u);
  // Nothing stands on the roof (the ceiling is a floor from above, but no way leads up).
  for (const Vec3& n : space.nav.nodes) EXPECT_LT(n.y, 3.0f);
}

TEST(PathPlanner, FlyingThroughTheRoomKeepsTheClearance) {
  test::TempDir dir;
  const World world(room_world(dir));
  PlannerOptions o;
  o.fly = true;
  const PlannedSpace space = plan_free_space(world, o);
  std::set<float> heights;
  for (const Vec3& n : space.nav.nodes) heights.insert(n.y);
  EXPECT_GE(heights.size(), 2u);
  check_every_kind(world, space, 150);
}

TEST(PathPlanner, NoFreeSpaceIsOneClearError) {
  test::TempDir dir;
  const World world(room_world(dir));
  PlannerOptions coarse;
  coarse.spacing = 1000;  // one column: fewer free nodes than a path needs
  try {
    plan_free_space(world, coarse);
    FAIL() << "planned";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("path planner: no free space to walk"), std::string::npos) << what;
    EXPECT_NE(what.find("lower --clearance or --spacing"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  PlannerOptions wide;
  wide.clearance = 20;  // wider than anywhere within reach of the room
  wide.reach = 10;
  EXPECT_THROW(plan_free_space(world, wide), Error);
  PlannerOptions bad;
  bad.clearance = -1;
  EXPECT_THROW(plan_free_space(world, bad), Error);
}

TEST(PathPlanner, SameSeedSameGraphAndPath) {
  test::TempDir dir;
  const World world(room_world(dir));
  const PlannedSpace a = plan_free_space(world), b = plan_free_space(world);
  ASSERT_EQ(a.nav.nodes, b.nav.nodes);
  ASSERT_EQ(a.nav.edges, b.nav.edges);
  PathParams p;
  p.kind = SessionKind::kRandom;
  p.seed = 9;
  const CameraPath x = generate_path(a.nav, p), y = generate_path(b.nav, p);
  ASSERT_EQ(x.frames.size(), y.frames.size());
  for (size_t i = 0; i < x.frames.size(); ++i) {
    ASSERT_EQ(x.frames[i].position, y.frames[i].position);
    ASSERT_EQ(x.frames[i].yaw_deg, y.frames[i].yaw_deg);
  }
}

TEST(PathPlanner, TheCommandPlansWhenTheWorldsGraphIsAnImportLoop) {
  test::TempDir dir;
  const std::string scene = dir.file("b.cwscene"), world = dir.file("b.cww"), path = dir.file("b.path");
  for (const std::string& command : {"import " + test::cgal_mesh("bunny00.off") + " -o " + scene, "build " + scene + " -o " + world}) {
    const auto r = test::run_cellwalk(command);
    ASSERT_EQ(r.exit_code, 0) << command << "\n" << r.output;
  }
  auto r = test::run_cellwalk("path " + world + " --frames 30 -o " + path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("does not lie in it; planning its free space"), std::string::npos) << r.output;
  r = test::run_cellwalk("path " + world + " --planner --fly --clearance 0.02 --frames 30 -o " + path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("flying"), std::string::npos) << r.output;
  // Bad values and planner options without --planner are refused with one line.
  // A grid too fine, in columns or (flying) in layers, is refused before anything is allocated.
  for (const char* args : {" --planner --clearance -1", " --planner --spacing nan", " --clearance 0.1",
                           " --planner --spacing 1e-20", " --planner --fly --spacing 0.0001"}) {
    r = test::run_cellwalk("path " + world + std::string(args) + " -o " + path);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
  }
  // A scene file cannot be planned on: it is not built.
  r = test::run_cellwalk("path " + scene + " --planner -o " + path);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("cellwalk build"), std::string::npos) << r.output;
}

// Issue 16: the bunny was in view on 8 of 90 frames of its import's path. An inspection path,
// and a planned flight that looks at the model, keep it in view on every frame.
TEST(PathPlanner, TheCommandMakesPathsThatKeepAModelInView) {
  test::TempDir dir;
  const std::string scene = dir.file("b.cwscene"), world = dir.file("b.cww"), path = dir.file("b.path");
  for (const std::string& command : {"import " + test::cgal_mesh("bunny00.off") + " -o " + scene, "build " + scene + " -o " + world}) {
    const auto r = test::run_cellwalk(command);
    ASSERT_EQ(r.exit_code, 0) << command << "\n" << r.output;
  }
  for (const std::string args : {" --kind inspect --frames 90", " --kind inspect --frames 40 --around bunny00#3",
                                  " --kind inspect --frames 40 --around 5", " --frames 90 --look-at centre"}) {
    const auto r = test::run_cellwalk("path " + world + args + " --coverage -o " + path);
    ASSERT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    const std::string frames = args.find("40") != std::string::npos ? "40" : "90";
    EXPECT_NE(r.output.find("in view (>= 1 % of the image) on " + frames + " of " + frames + " frames"), std::string::npos)
        << args << "\n" << r.output;
    EXPECT_EQ(read_path(path).frames.size(), size_t(std::stoi(frames)));
  }
  for (const char* args : {" --kind inspect --around nothing", " --kind inspect --around 99", " --around 1",
                           " --look-at 1,2", " --look-at 1,2,inf", " --kind inspect --planner"}) {
    const auto r = test::run_cellwalk("path " + world + std::string(args) + " -o " + path);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
  }
  const auto r = test::run_cellwalk("path " + scene + " --kind inspect --coverage -o " + path);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("cellwalk build"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace cellwalk
