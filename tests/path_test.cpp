#include "cellwalk/scene/path_generator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "cellwalk/core/error.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// A 3×3 street grid, 40 m blocks, eye height 1.7 m.
NavGraph grid_streets() {
  NavGraph g;
  for (int z = 0; z < 3; ++z)
    for (int x = 0; x < 3; ++x) g.nodes.push_back(Vec3(40.0f * x, 1.7f, 40.0f * z));
  for (uint32_t z = 0; z < 3; ++z)
    for (uint32_t x = 0; x < 3; ++x) {
      if (x < 2) g.edges.push_back({z * 3 + x, z * 3 + x + 1});
      if (z < 2) g.edges.push_back({z * 3 + x, (z + 1) * 3 + x});
    }
  return g;
}

float distance_to_graph(const NavGraph& g, const Vec3& p) {
  float best = 1e30f;
  for (auto [a, b] : g.edges) {
    Vec3 A = g.nodes[a], B = g.nodes[b];
    float t = std::clamp(glm::dot(p - A, B - A) / glm::dot(B - A, B - A), 0.0f, 1.0f);
    best = std::min(best, glm::distance(p, A + t * (B - A)));
  }
  return best;
}

TEST(Path, EveryKindStaysOnTheGraphAndIsDeterministic) {
  const NavGraph g = grid_streets();
  for (const char* kind : {"normal", "slow", "fast", "turning", "backward", "back-and-forth", "random"}) {
    PathParams p;
    p.kind = parse_session_kind(kind);
    p.frames = 900;
    p.seed = 5;
    CameraPath a = generate_path(g, p), b = generate_path(g, p);
    ASSERT_EQ(a.frames.size(), 900u) << kind;
    for (size_t i = 0; i < a.frames.size(); ++i) {
      ASSERT_LT(distance_to_graph(g, a.frames[i].position), 1e-3f) << kind << " frame " << i;
      ASSERT_EQ(a.frames[i].position, b.frames[i].position) << kind;
      ASSERT_EQ(a.frames[i].yaw_deg, b.frames[i].yaw_deg) << kind;
    }
  }
}

TEST(Path, KindsMoveAtTheirSpeeds) {
  const NavGraph g = grid_streets();
  auto travelled = [&](const char* kind) {
    PathParams p;
    p.kind = parse_session_kind(kind);
    p.frames = 300;
    CameraPath path = generate_path(g, p);
    double d = 0;
    for (size_t i = 1; i < path.frames.size(); ++i)
      d += glm::distance(path.frames[i].position, path.frames[i - 1].position);
    return d;
  };
  EXPECT_GT(travelled("fast"), 3.5 * travelled("normal"));
  EXPECT_GT(travelled("normal"), 2 * travelled("slow"));
}

TEST(Path, BackwardLooksAgainstTheDirectionOfTravel) {
  PathParams p;
  p.kind = SessionKind::kBackward;
  p.frames = 200;
  CameraPath path = generate_path(grid_streets(), p);
  Camera c;
  int against = 0;
  for (size_t i = 1; i < path.frames.size(); ++i) {
    apply(path.frames[i], c);
    Vec3 move = path.frames[i].position - path.frames[i - 1].position;
    if (glm::length(move) > 0 && glm::dot(c.forward(), move) < 0) ++against;
  }
  EXPECT_GT(against, 150);
}

TEST(Path, WritesAndReadsBack) {
  test::TempDir dir;
  PathParams p;
  p.kind = SessionKind::kTurning;
  p.frames = 50;
  CameraPath path = generate_path(grid_streets(), p);
  write_path(path, dir.file("p.txt"));
  CameraPath back = read_path(dir.file("p.txt"));
  ASSERT_EQ(back.frames.size(), path.frames.size());
  for (size_t i = 0; i < path.frames.size(); ++i) {
    EXPECT_NEAR(glm::distance(back.frames[i].position, path.frames[i].position), 0.0f, 1e-4f);
    EXPECT_NEAR(back.frames[i].yaw_deg, path.frames[i].yaw_deg, 1e-4f);
    EXPECT_NEAR(back.frames[i].time, path.frames[i].time, 1e-6);
  }
}

TEST(Path, MalformedFilesGiveErrorsNamingTheLine) {
  test::TempDir dir;
  struct Case {
    const char* text;
    const char* expect;
  } cases[] = {
      {"", "empty"},
      {"hello\n", ":1"},
      {"# cellwalk path 1\n0 1 2 3 4\n", ":2: expected 6 numbers"},
      {"# cellwalk path 1\n0 1 2 3 4 5 6\n", ":2: unexpected text"},
      {"# cellwalk path 1\n1 0 0 0 0 0\n0 0 0 0 0 0\n", ":3: time goes backwards"},
      {"# cellwalk path 1\n0 nan 0 0 0 0\n", ":2"},
      {"# cellwalk path 1\n# only comments\n", "no frames"},
  };
  for (const Case& c : cases) {
    std::ofstream(dir.file("bad.txt"), std::ios::trunc) << c.text;
    try {
      read_path(dir.file("bad.txt"));
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(read_path(dir.file("missing.txt")), Error);
}

// Issue 13, item 6: a model with coordinates near float's limit once gave a path of NaNs. The
// generator refuses a navigation graph beyond the coordinate bound, and the writer never writes
// a non-finite number, leaving an existing path file as it was.
TEST(Path, NeverWritesANonFiniteNumber) {
  NavGraph far = grid_streets();
  far.nodes[4] = Vec3(3e38f, 1.7f, -3e38f);
  try {
    generate_path(far, PathParams{});
    ADD_FAILURE() << "a graph beyond the bound gave a path";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("navigation node 4 (3e+38, 1.7, -3e+38) has a coordinate beyond 1e7 m"),
              std::string::npos) << e.what();
  }
  far.nodes[4] = Vec3(0.0f, std::nanf(""), 0.0f);
  EXPECT_THROW(generate_path(far, PathParams{}), Error);
  far.nodes[4] = Vec3(kMaxCoordinate, 1.7f, -kMaxCoordinate);  // the bound itself is fine
  EXPECT_NO_THROW(generate_path(far, PathParams{}));

  test::TempDir dir;
  const std::string file = dir.file("p.path");
  const CameraPath good = generate_path(grid_streets(), PathParams{});
  write_path(good, file);
  const std::vector<uint8_t> before = test::slurp(file);
  for (int field = 0; field < 6; ++field)
    for (const double bad : {double(std::nanf("")), double(INFINITY), -double(INFINITY)}) {
      CameraPath path = good;
      PathFrame& f = path.frames[7];
      const auto value = static_cast<float>(bad);
      if (field == 0) f.time = bad;
      if (field == 1) f.position.x = value;
      if (field == 2) f.position.y = value;
      if (field == 3) f.position.z = value;
      if (field == 4) f.yaw_deg = value;
      if (field == 5) f.pitch_deg = value;
      try {
        write_path(path, file);
        ADD_FAILURE() << "wrote " << bad << " in field " << field;
      } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()).rfind(file + ": frame 7 has a non-finite", 0), 0u) << e.what();
      }
      EXPECT_EQ(test::slurp(file), before);
    }
}

TEST(Path, UnknownKindAndEmptyGraphAreErrors) {
  EXPECT_THROW(parse_session_kind("sideways"), Error);
  EXPECT_THROW(generate_path(NavGraph{}, PathParams{}), Error);
}

// Issue 16: paths only knew streets. The inspection path keeps the whole box inside the view
// of every frame, within 90 % of its half-angles, at one distance that is the least that does
// (5 % nearer, some frame cuts it).
TEST(Path, InspectionKeepsTheWholeBoxInViewAtTheLeastDistance) {
  const Aabb boxes[] = {{{-0.5f, -0.5f, -0.4f}, {0.5f, 0.5f, 0.4f}},   // a scan
                        {{0, 0, 0}, {400, 30, 300}},                   // a flat plant
                        {{-2, 0, -2}, {2, 80, 2}},                      // a tower
                        {{-1e-3f, 7, 3}, {1e-3f, 7.002f, 3.002f}}};     // a tiny part, off the origin
  for (const Aabb& box : boxes) {
    PathParams p;
    p.frames = 240;
    const CameraPath path = inspection_path(box, p);
    ASSERT_EQ(path.frames.size(), 240u);
    const float R = glm::distance(path.frames[0].position, box.center());
    float least_yaw = 1e9f, most_yaw = -1e9f;
    Camera inner;  // the default lens narrowed to 90 % of its half-angles
    inner.fov_y_deg = glm::degrees(2 * std::atan(0.9f * std::tan(glm::radians(30.0f))));
    inner.near_plane = R * 1e-3f;
    inner.far_plane = R * 1e3f;
    for (const PathFrame& f : path.frames) {
      Camera cam = inner;
      apply(f, cam);
      EXPECT_EQ(Frustum(cam).classify(box), Containment::kInside);
      EXPECT_NEAR(glm::distance(f.position, box.center()), R, R * 1e-4f);
      EXPECT_NEAR(glm::dot(cam.forward(), glm::normalize(box.center() - f.position)), 1.0f, 1e-4f) << "aimed at the centre";
      const float elevation = glm::degrees(std::asin((f.position.y - box.center().y) / R));
      EXPECT_GE(elevation, 10.0f - 0.01f);
      EXPECT_LE(elevation, 35.0f + 0.01f);
      least_yaw = std::min(least_yaw, f.yaw_deg);
      most_yaw = std::max(most_yaw, f.yaw_deg);
    }
    EXPECT_GT(most_yaw - least_yaw, 350.0f) << "once around";
    bool cut = false;
    for (const PathFrame& f : path.frames) {
      PathFrame nearer = f;
      nearer.position = box.center() + 0.95f * (f.position - box.center());
      Camera cam = inner;
      apply(nearer, cam);
      cut |= Frustum(cam).classify(box) != Containment::kInside;
    }
    EXPECT_TRUE(cut) << "the distance is the least that keeps the box in view";
  }
  EXPECT_THROW(inspection_path(Aabb{}, PathParams{}), Error);
}

TEST(Path, AimAtLooksAtThePoint) {
  for (const Vec3 target : {Vec3(3, 1, -2), Vec3(-5, -4, 7), Vec3(0, 10, 0.01f)}) {
    PathFrame f;
    f.position = Vec3(1, 2, 3);
    aim_at(f, target);
    Camera cam;
    apply(f, cam);
    EXPECT_NEAR(glm::dot(cam.forward(), glm::normalize(target - f.position)), 1.0f, 1e-5f);
  }
}

}  // namespace
}  // namespace cellwalk
