// Helpers shared by the tests: real data paths, temporary folders, the cellwalk binary.
#pragma once

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
