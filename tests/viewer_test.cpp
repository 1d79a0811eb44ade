// Runs the viewer in a real window under Xvfb and checks what it showed.
#include <gtest/gtest.h>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include <cstdlib>
#include <fstream>
#include <set>
#include <sys/wait.h>

#include "cellwalk/store/world.hpp"

#include "cellwalk/scene/import.hpp"
#include "cellwalk/scene/path_generator.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

struct Png {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
};

Png load_png(const std::string& file) {
  Png png;
  int channels;
  unsigned char* data = stbi_load(file.c_str(), &png.width, &png.height, &channels, 3);
  if (data) {
    png.rgb.assign(data, data + size_t(png.width) * png.height * 3);
    stbi_image_free(data);
  }
  return png;
}

int distinct_colours(const Png& png) {
  std::set<uint32_t> colours;
  for (size_t i = 0; i + 2 < png.rgb.size(); i += 3)
    colours.insert(png.rgb[i] | png.rgb[i + 1] << 8 | png.rgb[i + 2] << 16);
  return static_cast<int>(colours.size());
}

class ViewerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0)
      FAIL() << "xvfb-run is missing: run scripts/setup (package xvfb)";
    scene_ = test::write_street_world(dir_, 30);
  }
  // `wrapper` runs before the binary inside the X server (e.g. "timeout -s TERM 5").
  test::CommandResult view(const std::string& args, const std::string& wrapper = "") {
    const std::string command = "xvfb-run -a -s '-screen 0 640x480x24' " + wrapper + " " + test::cellwalk_binary() +
                                " view " + scene_ + " --width 320 --height 240 " + args + " 2>&1";
    test::CommandResult r;
    FILE* pipe = popen(command.c_str(), "r");
    char buffer[4096];
    size_t n;
    while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) r.output.append(buffer, n);
    int status = pclose(pipe);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
  }
  test::TempDir dir_;
  std::string scene_;
};

TEST_F(ViewerTest, WindowShowsTheSceneAndStatistics) {
  auto r = view("--frames 3 --screenshot " + dir_.file("shot.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  Png png = load_png(dir_.file("shot.png"));
  ASSERT_EQ(png.width, 320) << r.output;
  ASSERT_EQ(png.height, 240);
  // Sky alone is one colour; boxes in several colours, shading and the text overlay add many.
  EXPECT_GT(distinct_colours(png), 20);
}

TEST_F(ViewerTest, BirdsEyeViewDiffersFromTheStreetView) {
  ASSERT_EQ(view("--frames 2 --screenshot " + dir_.file("street.png")).exit_code, 0);
  ASSERT_EQ(view("--frames 2 --birds-eye --screenshot " + dir_.file("bird.png")).exit_code, 0);
  Png a = load_png(dir_.file("street.png")), b = load_png(dir_.file("bird.png"));
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  size_t differing = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) differing += a.rgb[i] != b.rgb[i];
  EXPECT_GT(differing, a.rgb.size() / 10);
}

// Issue 16: the bird's-eye view drew the walker's choice at the walker's detail (0.3 fps over
// the demo city with brute). It now draws each chosen object no finer than its error from the
// top camera needs, and outlines the chosen set in yellow over every object's box.
TEST_F(ViewerTest, BirdsEyeViewDrawsTheChosenSetCoarserAndOutlined) {
  const Mesh bunny = import_model(test::cgal_mesh("bunny00.off")).objects.at(0).mesh;
  const Aabb b = bounds_of(bunny);
  std::vector<Object> objects;
  for (int i = 0; i < 6; ++i) {
    Object o;
    o.id = ObjectId(i);
    o.mesh = bunny;
    for (Vec3& p : o.mesh.positions) p += Vec3(float(i % 3) * 2 * b.size().x, 0, -float(i / 3 + 1) * 2 * b.size().z) - b.min;
    objects.push_back(std::move(o));
  }
  NavGraph nav;
  nav.nodes = {{b.size().x, b.size().y / 2, 0}, {b.size().x, b.size().y / 2, -b.size().z}};
  nav.edges = {{0, 1}};
  scene_ = test::write_world(dir_, objects, nav, "bunnies");
  const auto street = view("--frames 2 --strategy brute --json");
  const auto bird = view("--frames 2 --strategy brute --birds-eye --json --screenshot " + dir_.file("bird.png"));
  ASSERT_EQ(street.exit_code, 0) << street.output;
  ASSERT_EQ(bird.exit_code, 0) << bird.output;
  const double street_triangles = test::json_output(street).value("mean_triangles", 0.0);
  const double bird_triangles = test::json_output(bird).value("mean_triangles", 0.0);
  EXPECT_GT(street_triangles, 0.0);
  EXPECT_GT(bird_triangles, 0.0);
  EXPECT_LT(bird_triangles, street_triangles / 2) << "coarser from above";
  const Png png = load_png(dir_.file("bird.png"));
  size_t yellow = 0;
  for (size_t i = 0; i + 2 < png.rgb.size(); i += 3) yellow += png.rgb[i] == 255 && png.rgb[i + 1] == 210 && png.rgb[i + 2] == 0;
  EXPECT_GT(yellow, 20u) << "the chosen set's boxes";
}

TEST_F(ViewerTest, BirdsEyeViewOfStratifiedShowsTheViewcellInCyan) {
  const test::CommandResult built = test::run_cellwalk("stratify build " + scene_ + " --box 30 --resolution 32");
  ASSERT_EQ(built.exit_code, 0) << built.output;
  auto r = view("--strategy stratified --frames 2 --birds-eye --screenshot " + dir_.file("bird.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Png png = load_png(dir_.file("bird.png"));
  size_t cyan = 0;
  for (size_t i = 0; i + 2 < png.rgb.size(); i += 3) cyan += png.rgb[i] == 0 && png.rgb[i + 1] == 255 && png.rgb[i + 2] == 255;
  EXPECT_GT(cyan, 8u);
}

TEST_F(ViewerTest, ReplayedPathIsRecordedBackFaithfully) {
  PathParams p;
  p.frames = 5;
  World scene(scene_);
  write_path(generate_path(scene.info().nav, p), dir_.file("in.path"));
  // Replaying while recording: R cannot be pressed here, so the viewer records when given
  // --record together with --replay.
  auto r = view("--frames 5 --replay " + dir_.file("in.path") + " --record " + dir_.file("out.path"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CameraPath in = read_path(dir_.file("in.path")), out = read_path(dir_.file("out.path"));
  ASSERT_EQ(out.frames.size(), in.frames.size());
  for (size_t i = 0; i < in.frames.size(); ++i) {
    EXPECT_NEAR(glm::distance(in.frames[i].position, out.frames[i].position), 0.0f, 1e-4f);
    EXPECT_NEAR(in.frames[i].yaw_deg, out.frames[i].yaw_deg, 1e-3f);
  }
}

// Issue 16: --replay without --frames never ended, and a run ended by a signal wrote no
// screenshot.
TEST_F(ViewerTest, ReplayEndsAtThePathsEndAndWritesItsScreenshot) {
  PathParams p;
  p.frames = 7;
  World scene(scene_);
  write_path(generate_path(scene.info().nav, p), dir_.file("in.path"));
  const auto r = view("--replay " + dir_.file("in.path") + " --record " + dir_.file("out.path") + " --screenshot " +
                      dir_.file("end.png") + " --strategy lod --budget 64");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_path(dir_.file("out.path")).frames.size(), 7u);
  EXPECT_GT(distinct_colours(load_png(dir_.file("end.png"))), 10);
  // --json says the same (docs/json.md); the viewer's notes go to standard error.
  const auto j = view("--replay " + dir_.file("in.path") + " --record " + dir_.file("again.path") + " --strategy lod --json");
  ASSERT_EQ(j.exit_code, 0) << j.output;
  const nlohmann::json summary = test::json_output(j);
  EXPECT_EQ(summary.value("command", ""), "view") << j.output;
  EXPECT_EQ(summary.value("frames", 0), 7);
  EXPECT_EQ(summary.value("recorded", ""), dir_.file("again.path"));
  EXPECT_EQ(summary.value("recorded_frames", 0), 7);
  EXPECT_GT(summary.value("mean_triangles", 0.0), 0.0);
  EXPECT_GE(summary.value("worst_frame_ms", 0.0), summary.value("mean_frame_ms", 1.0));
  EXPECT_EQ(summary.value("stopped_by_signal", true), false);
}

TEST_F(ViewerTest, ASignalEndsTheRunAndTheScreenshotIsStillWritten) {
  const auto r = view("--screenshot " + dir_.file("last.png"), "timeout -s TERM 6");
  EXPECT_EQ(r.exit_code, 124) << "ended by the signal: " << r.output;
  EXPECT_GT(distinct_colours(load_png(dir_.file("last.png"))), 10) << r.output;
}

// Tab switches between the strategies given; each is made once at start, so one that cannot run
// on this world stops the viewer at once, naming it.
TEST_F(ViewerTest, SeveralStrategiesAreCheckedAtStart) {
  const auto both = view("--frames 2 --strategy lod --strategy brute --json");
  ASSERT_EQ(both.exit_code, 0) << both.output;
  EXPECT_EQ(test::json_output(both)["strategies"], nlohmann::json::array({"lod", "brute"}));
  const auto unusable = view("--frames 2 --strategy brute --strategy vlod");
  EXPECT_NE(unusable.exit_code, 0);
  EXPECT_NE(unusable.output.find("vlod"), std::string::npos) << unusable.output;
}

TEST_F(ViewerTest, NoDisplayGivesAClearError) {
  const std::string command = "env -u DISPLAY -u WAYLAND_DISPLAY " + test::cellwalk_binary() + " view " +
                              scene_ + " --frames 1 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[4096];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  int status = pclose(pipe);
  EXPECT_NE(WEXITSTATUS(status), 0);
  EXPECT_NE(output.find("cellwalk: "), std::string::npos) << output;
}

}  // namespace
}  // namespace cellwalk
