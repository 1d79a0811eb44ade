// Helpers shared by the tests: real data paths, temporary folders, the cellwalk binary.
#pragma once

#include <filesystem>
#include <cstdint>
#include <string>
#include <vector>

namespace cellwalk::test {

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
// Runs the cellwalk binary with `args` (a shell-quoted string) and captures its output.
CommandResult run_cellwalk(const std::string& args);

}  // namespace cellwalk::test

#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/scene/scene.hpp"

namespace cellwalk::test {

// A closed box mesh (24 vertices with face normals, 12 triangles).
Mesh box_mesh(const Aabb& box);

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
