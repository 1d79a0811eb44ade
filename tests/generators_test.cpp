// The world generators and their primitive shapes: determinism, streaming, the HDoV thesis's
// model sizes, navigation graphs that walk on free space, and the generate command.
#include "cellwalk/scene/generators.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <queue>
#include <set>
#include <string>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/process_memory.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "scene/shapes.hpp"
#include "precompute/occluders.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// Checks every object's contract, hashes the stream (FNV-1a over every field) and keeps only
// what the oracles need: bounds and per-name triangle counts.
class CheckingSink : public ObjectSink {
 public:
  void add(const Object& o) override {
    EXPECT_EQ(o.id, counts.objects) << "ids must be dense from 0 in order of add";
    EXPECT_FALSE(o.name.empty());
    EXPECT_GT(o.mesh.triangle_count(), 0u) << o.name;
    EXPECT_EQ(o.mesh.normals.size(), o.mesh.positions.size()) << o.name << " lacks normals";
    const Aabb b = bounds_of(o.mesh);
    EXPECT_EQ(o.bounds.min, b.min) << o.name;
    EXPECT_EQ(o.bounds.max, b.max) << o.name;
    validate(o.mesh, o.name);
    counts.count(o);
    bounds.push_back(o.bounds);
    names.push_back(o.name);
    kind_triangles[o.name.substr(0, o.name.find('/'))].push_back(o.mesh.triangle_count());
    mix(&o.id, sizeof o.id);
    mix(o.name.data(), o.name.size());
    mix(&o.color, sizeof o.color);
    mix(o.mesh.positions.data(), o.mesh.positions.size() * sizeof(Vec3));
    mix(o.mesh.normals.data(), o.mesh.normals.size() * sizeof(Vec3));
    mix(o.mesh.colors.data(), o.mesh.colors.size() * sizeof(Rgba8));
    mix(o.mesh.indices.data(), o.mesh.indices.size() * sizeof(uint32_t));
  }
  SceneCounts counts;
  uint64_t hash = 1469598103934665603ull;
  std::vector<Aabb> bounds;
  std::vector<std::string> names;
  std::map<std::string, std::vector<size_t>> kind_triangles;

 private:
  void mix(const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  }
};

struct CountingSink : ObjectSink {
  SceneCounts counts;
  void add(const Object& o) override { counts.count(o); }
};

using Generate = std::function<SceneInfo(ObjectSink&)>;

struct Run {
  SceneInfo info;
  CheckingSink sink;
};
std::unique_ptr<Run> run(const Generate& g) {
  auto r = std::make_unique<Run>();
  r->info = g(r->sink);
  return r;
}

CityParams small_city(uint64_t seed = 1) {
  CityParams p;
  p.objects = 400;
  p.landmark_fraction = 0.01;
  p.seed = seed;
  return p;
}
StratifiedCityParams small_stratified(uint64_t seed = 1) {
  StratifiedCityParams p;
  p.blocks_x = p.blocks_z = 3;
  p.seed = seed;
  return p;
}
PlantParams small_plant(uint64_t seed = 1) {
  PlantParams p;
  p.units_x = 2;
  p.units_z = 2;
  p.seed = seed;
  return p;
}
LevelParams small_level(uint64_t seed = 1) {
  LevelParams p;
  p.rooms_x = 3;
  p.rooms_z = 2;
  p.seed = seed;
  return p;
}
GridParams small_grid(uint64_t seed = 1) {
  GridParams p;
  p.mesh = test::cgal_mesh("bunny00.off");
  p.nx = 3;
  p.nz = 2;
  p.ny = 2;
  p.seed = seed;
  return p;
}

// The four generators at test size, by seed.
const std::map<std::string, std::function<Generate(uint64_t)>>& generators() {
  static const std::map<std::string, std::function<Generate(uint64_t)>> all = {
      {"city",
       [](uint64_t s) -> Generate {
         return [s](ObjectSink& k) { return generate_city(small_city(s), k); };
       }},
      {"stratified-city",
       [](uint64_t s) -> Generate {
         return [s](ObjectSink& k) { return generate_stratified_city(small_stratified(s), k); };
       }},
      {"plant",
       [](uint64_t s) -> Generate {
         return [s](ObjectSink& k) { return generate_plant(small_plant(s), k); };
       }},
      {"grid",
       [](uint64_t s) -> Generate {
         return [s](ObjectSink& k) { return generate_grid(small_grid(s), k); };
       }},
      {"level",
       [](uint64_t s) -> Generate {
         return [s](ObjectSink& k) { return generate_level(small_level(s), k); };
       }},
  };
  return all;
}

bool connected(const NavGraph& g) {
  if (g.nodes.empty()) return false;
  std::vector<std::vector<uint32_t>> next(g.nodes.size());
  for (auto [a, b] : g.edges) {
    next.at(a).push_back(b);
    next.at(b).push_back(a);
  }
  std::vector<bool> seen(g.nodes.size(), false);
  std::queue<uint32_t> todo;
  todo.push(0);
  seen[0] = true;
  size_t reached = 1;
  while (!todo.empty()) {
    const uint32_t n = todo.front();
    todo.pop();
    for (uint32_t m : next[n])
      if (!seen[m]) {
        seen[m] = true;
        ++reached;
        todo.push(m);
      }
  }
  return reached == g.nodes.size();
}

// Brute force: eye points every `step` along every edge, against every object's box.
void expect_nav_clear(const Run& r, float step) {
  size_t samples = 0;
  for (auto [a, b] : r.info.nav.edges) {
    const Vec3 p = r.info.nav.nodes[a], q = r.info.nav.nodes[b];
    const int n = std::max(1, static_cast<int>(glm::length(q - p) / step));
    for (int k = 0; k <= n; ++k, ++samples) {
      const Vec3 eye = p + (q - p) * (float(k) / float(n));
      for (size_t o = 0; o < r.sink.bounds.size(); ++o)
        ASSERT_FALSE(r.sink.bounds[o].contains(eye))
            << r.info.generator << ": object " << o << " blocks the walk at (" << eye.x << ", "
            << eye.y << ", " << eye.z << ")";
    }
  }
  EXPECT_GT(samples, 10u);
}

// ---- shapes ----------------------------------------------------------------------------

// Every triangle of a convex shape faces away from its centre, and normals are unit length.
void expect_closed_outward(const Mesh& m, size_t triangles) {
  EXPECT_EQ(m.triangle_count(), triangles);
  ASSERT_EQ(m.normals.size(), m.positions.size());
  const Vec3 centre = bounds_of(m).center();
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    const Vec3 a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]],
               c = m.positions[m.indices[t + 2]];
    EXPECT_GT(glm::dot(glm::cross(b - a, c - a), (a + b + c) / 3.0f - centre), 0.0f)
        << "triangle " << t / 3;
  }
  for (const Vec3& n : m.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-4f);
}

TEST(Shapes, CountsAndOrientation) {
  expect_closed_outward(shapes::box({2, 3, 4}), 12);
  expect_closed_outward(shapes::cylinder(1, 2, 16), 4 * 16 - 4);
  expect_closed_outward(shapes::cone(1, 2, 12), 2 * 12 - 2);
  expect_closed_outward(shapes::pyramid({2, 1, 2}), 6);
  expect_closed_outward(shapes::ellipsoid({1, 2, 1}, 16, 8), 2 * 16 * 7);
  EXPECT_EQ(shapes::cylinder(1, 2, 10, false).triangle_count(), 20u);
  EXPECT_EQ(shapes::torus(3, 1, 12, 8).triangle_count(), 2u * 12 * 8);
}

TEST(Shapes, BoxIsExactAndFlatShaded) {
  const Mesh m = shapes::box({2, 3, 4});
  const Aabb b = bounds_of(m);
  EXPECT_NEAR(b.min.x, -1, 1e-5);
  EXPECT_NEAR(b.max.z, 2, 1e-5);
  EXPECT_NEAR(b.min.y, 0, 1e-5);
  EXPECT_NEAR(b.max.y, 3, 1e-5);
  for (const Vec3& n : m.normals)  // flat faces: every normal is an axis
    EXPECT_NEAR(std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)}), 1.0f, 1e-5f);
}

TEST(Shapes, TorusBendOuterNormalsPointAway) {
  const Mesh m = shapes::torus(3, 0.5f, 8, 8, std::numbers::pi_v<float> / 2);
  EXPECT_EQ(m.triangle_count(), 2u * 8 * 8);
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Vec3 p = m.positions[i];
    const Vec3 axis = glm::normalize(Vec3(p.x, 0, p.z)) * 3.0f;  // the tube's centre line
    EXPECT_GT(glm::dot(m.normals[i], p - axis), 0.0f);
  }
}

// ---- every generator ---------------------------------------------------------------------

TEST(Generators, DeterministicAndSeeded) {
  for (const auto& [name, make] : generators()) {
    const auto a = run(make(1)), b = run(make(1)), c = run(make(2));
    EXPECT_EQ(a->sink.hash, b->sink.hash) << name;
    EXPECT_EQ(a->sink.counts.triangles, b->sink.counts.triangles) << name;
    EXPECT_NE(a->sink.hash, c->sink.hash) << name << ": seeds 1 and 2 gave the same world";
    EXPECT_EQ(a->info.seed, 1u) << name;
  }
}

TEST(Generators, NavGraphConnectedAndClearOfObjects) {
  for (const auto& [name, make] : generators()) {
    const auto r = run(make(3));
    EXPECT_TRUE(connected(r->info.nav)) << name;
    EXPECT_FALSE(r->info.bounds.empty()) << name;
    expect_nav_clear(*r, name == "grid" ? 0.05f : 1.0f);
  }
}

// ---- level --------------------------------------------------------------------------------

// The carved faces of rooms and corridors (an L, a T and a box touching another at a corner
// line) close the open space all together: welded by position, every edge is used by an even
// number of triangles (a T-junction would leave an edge used once), and each face's normal
// points into the open space, from which it is one-sided.
TEST(Level, CarvedFacesCloseTheSpaceWithoutTJunctions) {
  const std::vector<Aabb> spaces{{{0, 0, 0}, {4, 3, 4}}, {{4, 0, 1}, {7, 2.2f, 2.5f}}, {{5.5f, 0, 2.5f}, {7, 2.2f, 6}},
                                 {{2, 0, 4}, {3, 2.5f, 5}}, {{7, 0, 6}, {9, 3, 8}}};
  for (double tile : {0.0, 0.5, 1.3}) {
    Mesh all;
    size_t faces = 0;
    for (const CarvedFace& f : carved_faces(spaces, tile)) {
      ++faces;
      const Aabb b = bounds_of(f.mesh);
      const Vec3 inside = b.center() + 0.01f * f.normal, outside = b.center() - 0.01f * f.normal;
      const auto open = [&](const Vec3& p) {
        return std::any_of(spaces.begin(), spaces.end(), [&](const Aabb& s) { return s.contains(p); });
      };
      EXPECT_TRUE(open(inside) && !open(outside)) << "face " << faces << " at tile " << tile;
      for (size_t t = 0; t < f.mesh.triangle_count(); ++t) {
        const Vec3 a = f.mesh.positions[f.mesh.indices[3 * t]], b1 = f.mesh.positions[f.mesh.indices[3 * t + 1]],
                   c = f.mesh.positions[f.mesh.indices[3 * t + 2]];
        EXPECT_GT(glm::dot(glm::cross(b1 - a, c - a), f.normal), 0.0f) << "triangle wound against its face";
      }
      append(all, f.mesh);
    }
    EXPECT_TRUE(visibility::is_closed(all)) << "tile " << tile;
    EXPECT_GT(faces, 20u);
  }
}

// ---- city ---------------------------------------------------------------------------------

TEST(City, BuildingDesignsMatchThesisTable31) {
  CityParams p;
  p.objects = 600;
  p.landmark_fraction = 0.0;
  const auto r = run([&](ObjectSink& s) { return generate_city(p, s); });
  const std::map<std::string, double> thesis = {{"house1", 1812}, {"house2", 552}, {"house3", 240},
                                                {"tower1", 540},  {"tower2", 984}, {"tower3", 1702},
                                                {"tower4", 1348}, {"tower5", 1048}};
  for (const auto& [design, polygons] : thesis) {
    const auto& counts = r->sink.kind_triangles[design];
    ASSERT_FALSE(counts.empty()) << design << " never placed";
    for (size_t t : counts) EXPECT_EQ(t, counts.front()) << design << ": copies differ in size";
    EXPECT_NEAR(double(counts.front()), polygons, 0.15 * polygons) << design;
    std::printf("%s: %zu triangles (Table 3.1: %.0f)\n", design.c_str(), counts.front(), polygons);
  }
  EXPECT_EQ(r->sink.kind_triangles.count("landmark"), 0u);
}

TEST(City, ExactCountsLandmarkFractionAndReportedTotals) {
  CityParams p;
  p.objects = 1000;
  const auto r = run([&](ObjectSink& s) { return generate_city(p, s); });
  EXPECT_EQ(r->sink.counts.objects, 1000u);
  EXPECT_EQ(r->sink.kind_triangles["landmark"].size(), 10u);  // 1% of 1,000
  EXPECT_EQ(r->sink.counts.triangles, 1796164u);              // docs/generators.md

  p.objects = 20000;
  CountingSink big;
  generate_city(p, big);
  EXPECT_EQ(big.counts.objects, 20000u);
  EXPECT_EQ(big.counts.triangles, 35492082u);  // docs/generators.md; "millions" as the brief asks
}

// Streets are at least 10 m wide, so no object may come within 5 m of a street centre line
// (the nav graph's distinct x and z coordinates) — a stronger oracle than eye points alone.
TEST(City, ObjectsStayOffTheStreets) {
  const auto r = run([](ObjectSink& s) { return generate_city(small_city(5), s); });
  std::set<float> xs, zs;
  for (const Vec3& n : r->info.nav.nodes) {
    xs.insert(n.x);
    zs.insert(n.z);
  }
  EXPECT_GT(xs.size(), 3u);
  for (size_t o = 0; o < r->sink.bounds.size(); ++o) {
    const Aabb& b = r->sink.bounds[o];
    for (float x : xs)
      EXPECT_TRUE(b.max.x < x - 5 || b.min.x > x + 5) << r->sink.names[o] << " on street x=" << x;
    for (float z : zs)
      EXPECT_TRUE(b.max.z < z - 5 || b.min.z > z + 5) << r->sink.names[o] << " on street z=" << z;
  }
}

TEST(City, GivenExtentTooSmallIsAnError) {
  CityParams p;
  p.objects = 1000;
  p.extent = 100;
  CountingSink s;
  EXPECT_THROW(generate_city(p, s), Error);
}

TEST(City, HundredThousandObjectsStreamInBoundedMemory) {
  CityParams p;
  p.objects = 100000;
  p.landmark_fraction = 0.0005;  // 50 bunnies: keeps the run to seconds, still loads the model
  const uint64_t before = peak_rss_bytes() / 1024;
  CountingSink s;
  const SceneInfo info = generate_city(p, s);
  const uint64_t growth = peak_rss_bytes() / 1024 - before;
  EXPECT_EQ(s.counts.objects, 100000u);
  EXPECT_GT(s.counts.bytes, 4'000'000'000u);  // the world would not fit the budget it is held to
  EXPECT_LT(growth, 64u * 1024) << "peak RSS grew by " << growth << " KiB";
  EXPECT_TRUE(connected(info.nav));
}

// ---- stratified city, plant, grid ------------------------------------------------------

TEST(StratifiedCity, HasAppendixAParts) {
  StratifiedCityParams p;
  p.blocks_x = p.blocks_z = 6;
  const auto r = run([&](ObjectSink& s) { return generate_stratified_city(p, s); });
  for (const char* kind : {"street", "curb", "building", "park", "fountain", "tree"})
    EXPECT_FALSE(r->sink.kind_triangles[kind].empty()) << kind;
  EXPECT_EQ(r->sink.kind_triangles["curb"].size(), 36u);  // one ring per block
  EXPECT_LE(r->info.bounds.max.y, p.max_height + 1e-3);
}

TEST(Plant, DetailScalesTrianglesAndParts) {
  PlantParams p;
  p.units_x = p.units_z = 1;
  p.detail = 1;
  CheckingSink low, high;
  generate_plant(p, low);
  p.detail = 3;
  generate_plant(p, high);
  EXPECT_GT(high.counts.triangles, 5 * low.counts.triangles);
  EXPECT_GT(high.counts.objects, 2 * low.counts.objects);
  for (const char* part : {"tank", "boiler", "pipe", "walkway", "flange", "valve", "ladder"}) {
    bool found = false;
    for (const std::string& n : low.names) found |= n.find(part) != std::string::npos;
    EXPECT_TRUE(found) << part;
  }
}

TEST(Grid, LatticeOfUnitCopies) {
  const GridParams p = small_grid();
  const auto r = run([&](ObjectSink& s) { return generate_grid(p, s); });
  EXPECT_EQ(r->sink.counts.objects, 12u);
  const auto& tris = r->sink.kind_triangles["grid"];
  for (size_t t : tris) EXPECT_EQ(t, tris.front());
  const Vec3 size = r->sink.bounds.front().size();
  EXPECT_NEAR(std::max({size.x, size.y, size.z}), 1.0f, 1e-4f);
  GridParams tight = p;
  tight.spacing = 0.5;
  CountingSink s;
  EXPECT_THROW(generate_grid(tight, s), Error);
}

// ---- the command ----------------------------------------------------------------------------

TEST(GenerateCommand, WritesSceneAndPrintsCounts) {
  test::TempDir dir;
  const std::string out = dir.file("city.cwscene");
  const auto r = test::run_cellwalk("generate city --objects 300 --seed 4 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("city: 300 objects, "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bytes (raw), written to " + out), std::string::npos) << r.output;
  SceneReader scene(out);
  EXPECT_EQ(scene.object_count(), 300u);
  EXPECT_EQ(scene.info().generator, "city");
  EXPECT_TRUE(connected(scene.info().nav));

  const auto plant = test::run_cellwalk("generate plant --units-x 1 --units-z 2 --json -o " +
                                        dir.file("p.cwscene") + " --obj " + dir.file("p.obj"));
  ASSERT_EQ(plant.exit_code, 0) << plant.output;
  EXPECT_NE(plant.output.find("\"triangles\""), std::string::npos) << plant.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("p.obj")));

  EXPECT_NE(test::run_cellwalk("generate grid -o " + dir.file("g.cwscene")).exit_code,
            0);  // --mesh is required
  // A textured model placed by a generator is drawn in colour (a generated scene has no
  // textures): its merged mesh once kept the texture and the scene refused it.
  const auto textured = test::run_cellwalk("generate grid --mesh " + test::assimp_model("glTF2/BoxTextured-glTF-Binary/BoxTextured.glb") +
                                           " --nx 2 --nz 1 -o " + dir.file("t.cwscene"));
  ASSERT_EQ(textured.exit_code, 0) << textured.output;
  EXPECT_EQ(SceneReader(dir.file("t.cwscene")).read_object(0).mesh.texture, kNoTexture);
}

}  // namespace
}  // namespace cellwalk
