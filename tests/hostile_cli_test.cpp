// Hostile input to the cellwalk command line (tracker issue 13, docs/testing.md "Hostile
// input"): each case once broke a command (a destroyed input, a crash, a runaway, a silent
// wrong answer or a misleading message); now each fails at once with one line saying what,
// where and what to do, and leaves existing files as they were.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstring>

#include <filesystem>
#include <fstream>
#include <regex>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

namespace fs = std::filesystem;

// One small world, its scene and a path on it, shared by the cases (none of them writes there).
class HostileCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    scene_ = test::write_street_scene(*dir_, 8);
    world_ = test::write_street_world(*dir_, 8);
    path_ = dir_->file("street.path");
    const auto r = test::run_cellwalk("path " + world_ + " --frames 20 -o " + path_);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { delete dir_; }

  // Runs `args`, expects a refusal whose output holds every one of `needles`: a non-zero exit
  // (1 for an Error, CLI11's 1xx for a bad option), not a signal (the shell reports 128 + n).
  static std::string refused(const std::string& args, std::initializer_list<std::string> needles) {
    const auto r = test::run_cellwalk(args);
    EXPECT_TRUE(r.exit_code > 0 && r.exit_code < 128) << "exit " << r.exit_code << ": " << args << "\n" << r.output;
    for (const std::string& n : needles) EXPECT_NE(r.output.find(n), std::string::npos) << args << "\n" << r.output;
    return r.output;
  }

  static test::TempDir* dir_;
  static std::string scene_, world_, path_;
};
test::TempDir* HostileCli::dir_ = nullptr;
std::string HostileCli::scene_, HostileCli::world_, HostileCli::path_;

// A copy of the shared world in `dir`, for cases that try to destroy it.
std::string copy_of(const std::string& file, const test::TempDir& dir, const std::string& name) {
  const std::string copy = dir.file(name);
  fs::copy_file(file, copy);
  return copy;
}

std::string small_off(const test::TempDir& dir) {
  const std::string file = dir.file("m.off");
  std::ofstream(file) << "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  return file;
}

// --- 1. an output that is an input ---------------------------------------------------------

TEST_F(HostileCli, OutputThatIsTheInputIsRefusedAndTheInputSurvives) {
  test::TempDir dir;
  const std::string world = copy_of(world_, dir, "w.cww");
  const std::string scene = copy_of(scene_, dir, "s.cwscene");
  const std::string off = small_off(dir);
  fs::create_symlink(world, dir.file("link.cww"));
  const auto world_bytes = test::slurp(world), scene_bytes = test::slurp(scene), off_bytes = test::slurp(off);
  const std::string dot_spelling = (dir.path() / "." / "w.cww").string();
  for (const std::string& args : {"path " + world + " --frames 5 -o " + world,
                                  "path " + world + " --frames 5 -o " + dot_spelling,
                                  "path " + world + " --frames 5 -o " + dir.file("link.cww"),
                                  "render " + world + " -o " + world,
                                  "visual-build " + world + " -o " + world,
                                  "db " + world + " -o " + world,
                                  "build " + scene + " -o " + scene,
                                  "import " + off + " -o " + off,
                                  "import " + off + " -o " + dir.file("x.cwscene") + " --obj " + off,
                                  "generate grid --mesh " + off + " --nx 1 --nz 1 -o " + off,
                                  "walk " + world + " --path " + path_ + " -o " + world})
    refused(args, {"same file as the input"});
  EXPECT_EQ(test::slurp(world), world_bytes);
  EXPECT_EQ(test::slurp(scene), scene_bytes);
  EXPECT_EQ(test::slurp(off), off_bytes);
  refused("import " + off + " -o " + dir.file("y.cwscene") + " --obj " + dir.file("y.cwscene"), {"same file as the output"});
}

// --- 2. a glTF nested deeply enough to overflow tinygltf's recursive parse -----------------

TEST_F(HostileCli, DeeplyNestedGltfIsRefusedWithoutACrashOrATemporary) {
  test::TempDir dir;
  const std::string json = "{\"asset\":{\"version\":\"2.0\"},\"extras\":" + std::string(20000, '[') +
                           std::string(20000, ']') + "}";
  std::ofstream(dir.file("deep.gltf")) << json;
  // The GLB form: a 12-byte header, then the JSON chunk padded to 4 bytes.
  std::string padded = json;
  while (padded.size() % 4) padded += ' ';
  std::vector<uint8_t> glb(20 + padded.size());
  const auto put32 = [&](size_t at, uint32_t v) { std::memcpy(glb.data() + at, &v, 4); };
  std::memcpy(glb.data(), "glTF", 4);
  put32(4, 2);
  put32(8, uint32_t(glb.size()));
  put32(12, uint32_t(padded.size()));
  put32(16, 0x4E4F534Au);
  std::memcpy(glb.data() + 20, padded.data(), padded.size());
  test::spit(dir.file("deep.glb"), glb);
  for (const std::string& model : {dir.file("deep.gltf"), dir.file("deep.glb")}) {
    refused("import " + model + " -o " + dir.file("x.cwscene"), {model + "@", "nested deeper than"});
    for (const auto& entry : fs::directory_iterator(dir.path()))
      EXPECT_EQ(entry.path().filename().string().find("x.cwscene"), std::string::npos) << entry.path();
  }
}

// --- 3. GL start-up failure in the cube-map renderer -----------------------------------------

TEST_F(HostileCli, CubeMapResolutionsAreCheckedBeforeGl) {
  refused("pvs " + world_ + " --engine dov --cells grid:80 --dov-resolution 0 -o x.cww", {"--dov-resolution", "[4, 4096]"});
  refused("pvs " + world_ + " --engine dov --cells grid:80 --dov-resolution -1 -o x.cww", {"--dov-resolution"});
  refused("pvs " + world_ + " --engine conservative --check 1 --truth-resolution 0", {"--truth-resolution", "[16, 4096]"});
}

TEST_F(HostileCli, GlStartUpFailureInTheCubeMapRendererIsAnErrorNotAnAbort) {
  // glvnd finds no EGL vendor: the renderer's thread fails to make its context (exact cube maps
  // render through GL; the default, rays, needs none).
  test::TempDir dir;
  const std::string command = "env __EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json " + test::cellwalk_binary() + " pvs " + world_ +
                              " --engine dov --dov-cubes exact --cells grid:80 --dov-resolution 16 -o " + dir.file("y.cww") + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[1024];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  const int status = pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 1) << output;  // the shell reports a SIGABRT as 134
  EXPECT_EQ(output.find("terminate called"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir.file("y.cww")));
}

// --- 4. NaN and infinities -------------------------------------------------------------------

TEST_F(HostileCli, NonFiniteNumbersAreRefused) {
  test::TempDir dir;
  refused("build " + scene_ + " -o " + dir.file("w.cww") + " --lod-ratio nan", {"--lod-ratio", "not a finite number"});
  refused("visual-build " + world_ + " -o " + dir.file("w.hdov") + " --lod-ratio nan", {"--lod-ratio", "not a finite number"});
  refused("walk " + world_ + " --path " + path_ + " -o " + dir.file("o") + " --budget nan", {"--budget", "not a finite number"});
  refused("walk " + world_ + " --path " + path_ + " -o " + dir.file("o") + " --far nan", {"--far", "not a finite number"});
  refused("walk " + world_ + " --path " + path_ + " -o " + dir.file("o") + " --near inf", {"--near", "not a finite number"});
  refused("pvs " + world_ + " --cells grid:inf -o " + dir.file("w.cww"), {"grid:inf", "finite positive"});
  refused("pvs " + world_ + " --cells grid:nan -o " + dir.file("w.cww"), {"grid:nan", "finite positive"});
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

// --- 5. runaways: counts and sizes that would run for hours -------------------------------

TEST_F(HostileCli, HugeOrNegativeCountsAreRefusedAtOnce) {
  test::TempDir dir;
  const std::string out = " -o " + dir.file("c.cwscene");
  refused("generate city --objects -5" + out, {"--objects", "-5 is outside [1, 10000000]"});
  refused("generate city --objects 4294967297" + out, {"--objects", "outside [1, 10000000]"});
  refused("generate grid --mesh " + small_off(dir) + " --nx 10000 --nz 10000" + out, {"grid", "100000000 objects"});
  refused("generate stratified-city --blocks-x 10000 --blocks-z 10000" + out, {"stratified-city", "more than the most"});
  refused("generate plant --units-x 1000 --units-z 1000" + out, {"plant", "more than the most"});
  refused("pvs " + world_ + " --engine conservative --cells grid:0.001 -o " + dir.file("w.cww"), {"view cells", "1000000 cells"});
  refused("pvs " + world_ + " --cells octree:8:100:40 -o " + dir.file("w.cww"), {"octree depth"});
  refused("pvs " + world_ + " --engine conservative --smallest-hole 0.0001 -o " + dir.file("w.cww"),
          {"--smallest-hole", "voxels", "larger --smallest-hole"});
  refused("path " + world_ + " --fps 1e-30 --frames 5 -o " + dir.file("p.path"), {"--fps", "outside [0.1, 1000]"});
  refused("path " + world_ + " --frames 100000000 -o " + dir.file("p.path"), {"--frames"});
  EXPECT_FALSE(fs::exists(dir.file("c.cwscene")));
}

// --- 6. a lens that draws nothing ------------------------------------------------------------

TEST_F(HostileCli, FarPlaneBeforeTheNearPlaneIsRefused) {
  test::TempDir dir;
  refused("walk " + world_ + " --path " + path_ + " -o " + dir.file("o") + " --near 10 --far 1", {"far plane must lie beyond"});
  refused("render " + world_ + " -o " + dir.file("x.png") + " --near 10 --far 1", {"far plane must lie beyond"});
  refused("walk " + world_ + " --path " + path_ + " -o " + dir.file("o") + " --fov 180", {"--fov"});
  EXPECT_FALSE(fs::exists(dir.file("o")));
}

// --- 8, 10. threads, shards, counts ---------------------------------------------------------

TEST_F(HostileCli, ThreadCountsAreBounded) {
  test::TempDir dir;
  refused("build " + scene_ + " -o " + dir.file("w.cww") + " --threads 100000", {"--threads", "outside [0, 256]"});
  refused("build " + scene_ + " -o " + dir.file("w.cww") + " --threads -1", {"--threads", "outside [0, 256]"});
  refused("pvs " + world_ + " --threads -1 -o " + dir.file("w.cww"), {"--threads"});
}

TEST_F(HostileCli, NonsenseCountsAndShardsAreRefused) {
  test::TempDir dir;
  const std::string pvs = "pvs " + world_ + " -o " + dir.file("w.cww");
  refused(pvs + " --shard 1/2junk", {"--shard '1/2junk'", "0 <= i < N"});
  refused(pvs + " --shard 2/2", {"--shard '2/2'"});
  refused(pvs + " --shard /2", {"--shard '/2'"});
  refused(pvs + " --points 0", {"--points"});
  refused(pvs + " --rays -1", {"--rays"});
  refused(pvs + " --engine conservative --refine -1", {"--refine"});
  refused(pvs + " --engine conservative --smallest-hole nan", {"--smallest-hole"});
  refused(pvs + " --engine conservative --smallest-hole 0", {"--smallest-hole"});
  refused(pvs + " --engine sampling --smallest-hole 1", {"--smallest-hole", "conservative engine only"});
  refused(pvs + " --engine conservative --smallest-occluder 1", {"--smallest-occluder", "--smallest-hole"});
  refused(pvs + " --check 1 --truth-points -5", {"--truth-points"});
  refused("compare " + world_ + " --path " + path_ + " -o " + dir.file("o") + " --images -1", {"--images"});
  refused("build " + scene_ + " -o " + dir.file("w.cww") + " --page-size 0", {"--page-size", "power of two"});
  refused("build " + scene_ + " -o " + dir.file("w.cww") + " --page-size 3000", {"--page-size", "power of two"});
}

TEST_F(HostileCli, BoundsAreReadable) {
  // CLI11's PositiveNumber printed its bound as 300 digits.
  const std::string out = refused("path " + world_ + " --fps -1 -o x.path", {"--fps"});
  EXPECT_FALSE(std::regex_search(out, std::regex("[0-9]{20}"))) << out;
}

TEST_F(HostileCli, UnknownSubcommandIsNamed) {
  refused("frobnicate x", {"unknown subcommand 'frobnicate'", "generate, import"});
  refused("generate town -o x", {"unknown subcommand 'town'", "city"});
}

// --- 10. paths: the world they were made for, their version, a directory -------------------

TEST_F(HostileCli, PathOfAnotherWorldIsWarnedAbout) {
  test::TempDir dir;
  const std::string other = test::write_street_world(dir, 4, 7);
  const std::string other_path = dir.file("other.path");
  ASSERT_EQ(test::run_cellwalk("path " + other + " --frames 5 -o " + other_path).exit_code, 0);
  const CameraPath made = read_path(other_path);
  EXPECT_TRUE(made.world.known());
  // Walked on its own world: no warning; on the shared world: a warning, and the walk still runs.
  auto r = test::run_cellwalk("walk " + other + " --path " + other_path + " -o " + dir.file("a"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
  r = test::run_cellwalk("walk " + world_ + " --path " + other_path + " -o " + dir.file("b"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: " + other_path + ": made for the world"), std::string::npos) << r.output;
  // A path file without the line (older files, recorded paths) walks without a warning.
  CameraPath plain = made;
  plain.world = {};
  write_path(plain, dir.file("plain.path"));
  r = test::run_cellwalk("walk " + world_ + " --path " + dir.file("plain.path") + " -o " + dir.file("c"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
}

TEST_F(HostileCli, PathFileOfAnotherVersionOrADirectoryIsRefused) {
  test::TempDir dir;
  std::ofstream(dir.file("v2.path")) << "# cellwalk path 2\n0 0 1.7 0 0 0\n";
  try {
    read_path(dir.file("v2.path"));
    ADD_FAILURE() << "version 2 accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("version '2' is not supported"), std::string::npos) << e.what();
  }
  try {
    read_path(dir.path().string());
    ADD_FAILURE() << "a directory accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
}

// Issue 16: `walk x.cwscene` said "bad magic". A scene where a world is wanted, and a world
// where a scene is wanted, say which file it is and what to do.
TEST_F(HostileCli, SceneAndWorldFilesSwappedSayWhatToDo) {
  refused("walk " + scene_ + " --path " + path_ + " -o " + dir_->file("w"), {scene_, "is a scene file", "cellwalk build"});
  refused("info " + path_, {path_, "not a cellwalk scene file", "cellwalk generate or import"});
  refused("build " + world_ + " -o " + dir_->file("again.cww"), {world_, "is a world file"});
}

// --- 10. a full disk, a UTF-16 model, a small budget ----------------------------------------

TEST_F(HostileCli, WalkOnAFullDiskLeavesNoEmptyFolder) {
  test::TempDir dir;
  const std::string out = dir.file("new/walk");
  // A file-size limit of 0 makes every write fail as a full disk would (SIGXFSZ ignored).
  const std::string command = "bash -c \"trap '' XFSZ; ulimit -f 0; exec " + test::cellwalk_binary() + " walk " +
                              world_ + " --path " + path_ + " -o " + out + "\" 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[1024];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  const int status = pclose(pipe);
  EXPECT_NE(status, 0) << output;
  EXPECT_FALSE(fs::exists(dir.file("new"))) << output;
}

TEST_F(HostileCli, Utf16ObjIsNamedAsUtf16) {
  test::TempDir dir;
  const std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::vector<uint8_t> utf16{0xFF, 0xFE};
  for (char c : text) {
    utf16.push_back(uint8_t(c));
    utf16.push_back(0);
  }
  test::spit(dir.file("u.obj"), utf16);
  refused("import " + dir.file("u.obj") + " -o " + dir.file("u.cwscene"), {dir.file("u.obj") + ":1", "UTF-16", "UTF-8"});
  utf16.erase(utf16.begin(), utf16.begin() + 2);  // no byte-order mark
  test::spit(dir.file("u.obj"), utf16);
  refused("import " + dir.file("u.obj") + " -o " + dir.file("u.cwscene"), {"UTF-16"});
}

TEST_F(HostileCli, BudgetRefusalsDoNotRoundToZero) {
  test::TempDir dir;
  // 0.001 MiB: the message printed "budget of 0 MiB".
  const std::string out = refused("walk " + world_ + " --path " + path_ + " -o " + dir.file("o") + " --budget 0.001",
                                  {"budget of 1.0 KiB"});
  EXPECT_EQ(out.find(" 0 MiB"), std::string::npos) << out;
}

// An unknown strategy name recursed without end (a stack overflow) instead of naming the
// strategies there are.
TEST_F(HostileCli, UnknownStrategyIsNamedWithTheStrategiesThereAre) {
  test::TempDir dir;
  for (const std::string command : {"walk", "compare"})
    refused(command + " " + world_ + " --path " + path_ + " -o " + dir.file(command) + " --strategy no-such",
            {"no-such", "brute", "visual"});
}

// A vLOD option given to another engine was ignored without a word.
TEST_F(HostileCli, VlodLevelOptionsNeedTheVlodEngine) {
  refused("pvs " + world_ + " --engine sampling --lod-height 720", {"--lod-height", "--engine vlod"});
}

}  // namespace
}  // namespace cellwalk
