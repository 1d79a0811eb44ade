// Helpers shared by the tests: real data paths, temporary folders, the cellwalk binary.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <cstdint>
#include <string>
#include <vector>

namespace cellwalk::test {

// True in a build under AddressSanitizer, whose allocator quarantines freed memory: resident
// bytes then say nothing about what the code holds, so tests of RSS bounds skip them.
constexpr bool kUnderAddressSanitizer =
#if defined(__SANITIZE_ADDRESS__)
    true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    true;
#else
    false;
#endif
#else
    false;
#endif

// A path under the source tree, e.g. source_path("tests/data/broken/empty.off").
std::string source_path(const std::string& relative);
// A mesh from the CGAL archive unpacked by scripts/setup, e.g. cgal_mesh("bunny00.off").
// Fails the test (GTEST_SKIP is not used: the data is a declared dependency) if it is missing.
std::string cgal_mesh(const std::string& name);
// A model from Debian's assimp-testmodels, e.g. assimp_model("glTF2/.../2CylinderEngine.glb").
std::string assimp_model(const std::string& relative);

// A whole file's bytes, and writing bytes as a whole file (replacing it).
std::vector<uint8_t> slurp(const std::string& file);
void spit(const std::string& file, const std::vector<uint8_t>& bytes);

// A fresh empty directory, removed when the object goes out of scope.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

struct CommandResult {
  int exit_code = 0;
  std::string output;          // stdout and stderr together
  uint64_t max_rss_bytes = 0;  // the command's peak resident memory, from the kernel (wait4)
};
// The JSON a command printed with --json (docs/json.md: one object, from the first '{' of the
// output on); null when there is none or it does not parse.
nlohmann::json json_output(const CommandResult& r);
// Of a walk's or a compare's JSON, the summary of its only run ("runs"[0]); null when absent.
nlohmann::json only_run(const CommandResult& r);
// The cellwalk binary the tests run: this build's, or $CELLWALK_BINARY when set (to run the
// command tests against another build, e.g. the one before a fix).
std::string cellwalk_binary();
// Runs the cellwalk binary with `args` (a shell-quoted string) and captures its output.
CommandResult run_cellwalk(const std::string& args);

// Inputs the tests of a suite read and never write, made once for all of them: ctest runs each
// test in a process of its own, so a suite's SetUpTestSuite would otherwise make them again for
// every test. `commands` are cellwalk arguments in which "{dir}" stands for the folder. The
// folder lies beside the test binary, named for `name` and a hash of the commands and of the
// cellwalk binary (path, size, time), so a rebuilt binary makes them anew.
// Process-safe: made under an exclusive lock, and marked complete only after the last command
// succeeded; a failing command fails the calling test and leaves the folder to be made again.
// A test that changes an input works on a copy (in a TempDir of its own).
class SharedInputs {
 public:
  SharedInputs(const std::string& name, const std::vector<std::string>& commands);
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  bool complete() const { return complete_; }

 private:
  std::filesystem::path path_;
  bool complete_ = false;
};

}  // namespace cellwalk::test

#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/scene/scene.hpp"

namespace cellwalk::test {

// A closed box mesh (24 vertices with face normals, 12 triangles).
Mesh box_mesh(const Aabb& box);

// The planar quad a, b, c, d (in that order around it; two triangles, one face normal). Open.
Mesh quad_mesh(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// `mesh` as exporters write a double-sided surface: every triangle a second time in the
// opposite winding, on vertices of its own with the normals flipped.
Mesh double_sided(const Mesh& mesh);

// A 10 × 3 × 10 m room (x, z in [0, 10], floor y = 0, ceiling y = 3) of double-sided quads, the
// wall z = 0 with a 2 × 2.2 m doorway at x in [4, 6]: a surface that encloses nothing.
Mesh double_sided_room_with_door();

// Writes a scene of `count` boxes beside a street along the x axis (z = 0), with a
// navigation graph down the street, and returns its path. Deterministic in `seed`.
std::string write_street_scene(const TempDir& dir, int count, uint64_t seed = 1);
// The same scene built into a world file (cellwalk build with default parameters).
std::string write_street_world(const TempDir& dir, int count, uint64_t seed = 1);

}  // namespace cellwalk::test

#include <vector>

namespace cellwalk::test {

// Writes `objects` (ids must be 0, 1, 2 ... in order; bounds are recomputed from the meshes)
// as a scene with navigation graph `nav`, builds it into a world file named `name`.cww and
// returns its path.
std::string write_world(const TempDir& dir, const std::vector<Object>& objects, const NavGraph& nav,
                        const std::string& name = "objects");

}  // namespace cellwalk::test

#include <algorithm>
#include <optional>
#include <set>

#include "cellwalk/core/random.hpp"
#include "cellwalk/precompute/conservative_visibility.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk::test {

// The world's drawn geometry (level 0, decoded) and brute-force rays against it.
class RayOracle {
 public:
  explicit RayOracle(const World& world) {
    for (ObjectId id = 0; id < world.object_count(); ++id) {
      meshes_.push_back(world.decode_level(id, 0, world.read_level(id, 0)));
      boxes_.push_back(bounds_of(meshes_.back()));
      std::vector<double> cdf;
      double total = 0;
      const Mesh& m = meshes_.back();
      for (size_t t = 0; t < m.triangle_count(); ++t) {
        total += glm::length(glm::cross(m.positions[m.indices[3 * t + 1]] - m.positions[m.indices[3 * t]],
                                        m.positions[m.indices[3 * t + 2]] - m.positions[m.indices[3 * t]]));
        cdf.push_back(total);
      }
      cdfs_.push_back(std::move(cdf));
    }
  }

  // The objects first hit by rays from `points` of the cell towards random points of every
  // object's surface (rays_per_object per point and object not yet seen).
  std::set<ObjectId> visible(const Aabb& cell, Random& rng, int points, int rays_per_object) const {
    std::set<ObjectId> seen;
    for (int i = 0; i < points; ++i) {
      const Vec3 p = sample_point(cell, i, rng);
      for (ObjectId target = 0; target < meshes_.size(); ++target)
        for (int r = 0; r < rays_per_object && !seen.count(target); ++r)
          if (auto hit = first_hit(p, surface_point(target, rng))) seen.insert(*hit);
    }
    return seen;
  }

  // The first object the segment from → to meets (to lies on a surface: up to it, inclusive).
  std::optional<ObjectId> first_hit(const Vec3& from, const Vec3& to) const {
    const glm::dvec3 o(from), d = glm::dvec3(to) - o;
    double best = 1.0 + 1e-6;
    std::optional<ObjectId> hit;
    for (ObjectId id = 0; id < meshes_.size(); ++id) {
      if (!segment_near_box(o, d, boxes_[id], best)) continue;
      const Mesh& m = meshes_[id];
      for (size_t t = 0; t < m.triangle_count(); ++t) {
        const double at = intersect(o, d, m, t);
        if (at > 1e-9 && at < best) best = at, hit = id;
      }
    }
    return hit;
  }

 private:
  std::vector<Mesh> meshes_;
  std::vector<Aabb> boxes_;
  std::vector<std::vector<double>> cdfs_;

  // Corners first, then face points, then interior points.
  static Vec3 sample_point(const Aabb& c, int i, Random& rng) {
    if (i < 8)
      return {i & 1 ? c.max.x : c.min.x, i & 2 ? c.max.y : c.min.y, i & 4 ? c.max.z : c.min.z};
    Vec3 p(rng.uniform(c.min.x, c.max.x), rng.uniform(c.min.y, c.max.y), rng.uniform(c.min.z, c.max.z));
    if (i % 2 == 0) {
      const int axis = i / 2 % 3;
      p[axis] = (i / 6) % 2 ? c.max[axis] : c.min[axis];
    }
    return p;
  }

  Vec3 surface_point(ObjectId id, Random& rng) const {
    const std::vector<double>& cdf = cdfs_[id];
    const size_t t = std::min(cdf.size() - 1, size_t(std::lower_bound(cdf.begin(), cdf.end(),
                                                                       rng.uniform() * cdf.back()) - cdf.begin()));
    double u = rng.uniform(), v = rng.uniform();
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Mesh& m = meshes_[id];
    const Vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]],
               c = m.positions[m.indices[3 * t + 2]];
    return a + float(u) * (b - a) + float(v) * (c - a);
  }

  static bool segment_near_box(const glm::dvec3& o, const glm::dvec3& d, const Aabb& b, double limit) {
    double t0 = 0, t1 = limit;
    for (int a = 0; a < 3; ++a) {
      const double lo = b.min[a] - 1e-4, hi = b.max[a] + 1e-4;
      if (d[a] == 0) {
        if (o[a] < lo || o[a] > hi) return false;
        continue;
      }
      double n = (lo - o[a]) / d[a], f = (hi - o[a]) / d[a];
      if (n > f) std::swap(n, f);
      t0 = std::max(t0, n), t1 = std::min(t1, f);
      if (t0 > t1) return false;
    }
    return true;
  }

  // Möller–Trumbore; the segment parameter of the hit, or -1. Edges count as hits (a ray
  // grazing an edge sees it: the oracle leans towards "visible").
  static double intersect(const glm::dvec3& o, const glm::dvec3& d, const Mesh& m, size_t t) {
    const glm::dvec3 a(m.positions[m.indices[3 * t]]), b(m.positions[m.indices[3 * t + 1]]),
        c(m.positions[m.indices[3 * t + 2]]);
    const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-18) return -1;
    const glm::dvec3 s = o - a;
    const double u = glm::dot(s, p) / det;
    if (u < -1e-9 || u > 1 + 1e-9) return -1;
    const glm::dvec3 q = glm::cross(s, e1);
    const double v = glm::dot(d, q) / det;
    if (v < -1e-9 || u + v > 1 + 1e-9) return -1;
    return glm::dot(e2, q) / det;
  }
};

// A world written from `objects` (as write_world) and what the conservative engine finds
// visible from a cell of it.
struct ObjectScene {
  TempDir dir;
  std::unique_ptr<World> world;
  explicit ObjectScene(const std::vector<Object>& objects)
      : world(std::make_unique<World>(write_world(dir, objects, NavGraph{}))) {}
  std::vector<ObjectId> visible(const Aabb& cell, const ConservativeParams& params = {}) const {
    return make_conservative_engine(*world, params)->compute(ViewCell{0, cell, 0, false}).objects;
  }
  bool sees(const Aabb& cell, ObjectId id, const ConservativeParams& params = {}) const {
    const auto set = visible(cell, params);
    return std::binary_search(set.begin(), set.end(), id);
  }
};

}  // namespace cellwalk::test
