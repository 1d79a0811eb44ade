// Tests of the `lod` baseline (src/systems/brute/brute.cpp): frustum culling plus each object
// at the coarsest level whose screen-space error from the eye is under the bound, checked
// against the bound computed here by hand, and its picture against ground truth.
#include <gtest/gtest.h>

#include <cmath>

#include "cellwalk/core/error.hpp"
#include "cellwalk/lod/screen_error.hpp"
#include "cellwalk/metrics/fidelity.hpp"
#include "cellwalk/render/renderer.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/store/world.hpp"
#include "systems/brute/brute.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// Bunnies down the -z axis from 1 to 200 of their own sizes away, alternately left and right
// of it so that none hides the next, and one behind the eye.
std::string write_bunny_row(const test::TempDir& dir) {
  const Mesh bunny = import_model(test::cgal_mesh("bunny00.off")).objects.at(0).mesh;
  const Aabb b = bounds_of(bunny);
  const float size = glm::length(b.size());
  std::vector<Object> objects;
  for (float k : {1.0f, 4.0f, 15.0f, 60.0f, 200.0f, -5.0f}) {
    Object o;
    o.id = static_cast<ObjectId>(objects.size());
    o.mesh = bunny;
    const float side = objects.size() % 2 ? 0.4f : -0.4f;
    for (Vec3& p : o.mesh.positions) p += Vec3(side * k * size, 0, -k * size) - b.center();
    objects.push_back(std::move(o));
  }
  NavGraph nav;
  nav.nodes = {{0, 0, 0}, {0, 0, -1}};
  nav.edges = {{0, 1}};
  return test::write_world(dir, objects, nav, "bunny_row");
}

// The bound by hand: error · (H / 2) / tan(fov_y / 2) / (L · cos² φ), tan φ = tan(fov_y / 2) · √(1 + a²).
float bound_px(float error, float distance, const Camera& cam, float height) {
  const float t = std::tan(glm::radians(cam.fov_y_deg) / 2);
  const float cos_phi = std::cos(std::atan(t * std::sqrt(1 + cam.aspect * cam.aspect)));
  return error * (height / 2 / t) / (distance * cos_phi * cos_phi);
}

TEST(LodBaseline, EachVisibleObjectGetsTheCoarsestLevelUnderTheBound) {
  test::TempDir dir;
  const World world(write_bunny_row(dir));
  Camera cam;
  cam.position = Vec3(0.01f, 0.02f, 0.5f * glm::length(world.object(0).bounds.size()));
  cam.aspect = 4.0f / 3.0f;
  for (float px : {1.0f, 0.25f, 4.0f}) {
    StrategyOptions options;
    options.viewport_height_px = 480;
    const std::string name = "lod:px=" + std::to_string(px);
    std::unique_ptr<Strategy> lod = make_strategy(name, world, options);
    BruteStrategy brute(world, options, true);
    std::vector<DrawItem> items, brute_items;
    FrameStats stats;
    lod->select(cam, items, stats);
    brute.select(cam, brute_items, stats);
    ASSERT_EQ(items.size(), brute_items.size()) << name;
    ASSERT_EQ(items.size(), world.object_count() - 1) << "the bunny behind the eye is culled";
    uint32_t coarsened = 0;
    for (size_t i = 0; i < items.size(); ++i) {
      ASSERT_EQ(items[i].id, brute_items[i].id);
      const ObjectRecord& o = world.object(items[i].id);
      const float d = distance_to_box(cam.position, o.bounds);
      // Every level up to the chosen one is under the bound; the next is not (or there is none).
      for (uint32_t l = 1; l <= items[i].lod; ++l) {
        EXPECT_LT(bound_px(world.lod(items[i].id, l).error, d, cam, 480), px * 1.0001f) << name << " level " << l;
      }
      if (items[i].lod + 1 < o.lod_count) {
        EXPECT_GE(bound_px(world.lod(items[i].id, items[i].lod + 1).error, d, cam, 480), px * 0.9999f) << name;
      }
      coarsened += items[i].lod > 0;
    }
    for (size_t i = 1; i < items.size(); ++i) EXPECT_LE(items[i - 1].lod, items[i].lod) << name << ": farther, coarser";
    EXPECT_GT(coarsened, 0u) << name << ": far bunnies are drawn coarser";
  }
}

TEST(LodBaseline, DrawsFewerTrianglesWithTheSameObjectsSeen) {
  test::TempDir dir;
  const World world(write_bunny_row(dir));
  auto context = GlContext::headless();
  RenderSettings settings;
  settings.width = 160;
  settings.height = 120;
  Renderer renderer(settings);
  StrategyOptions options;
  options.viewport_height_px = 120;
  std::unique_ptr<Strategy> lod = make_strategy("lod", world, options);
  BruteStrategy truth(world, options, false), brute(world, options, true);
  CameraPath path;
  const float size = glm::length(world.object(0).bounds.size());
  for (int i = 0; i < 4; ++i) path.frames.push_back({i / 30.0, Vec3(0.02f * i, 0.01f, 3.0f * size), 0.0f, 0.0f});
  Camera lens;
  lens.aspect = 160.0f / 120.0f;
  CompareOptions every_frame;
  every_frame.every = 1;
  const FidelitySummary s = summarize(compare(path, lens, *lod, truth, renderer, every_frame));
  EXPECT_EQ(s.missed_objects, 0u);
  EXPECT_GE(s.visible_objects, 4u * 4u);
  EXPECT_LE(s.max_pixel_error_p999_px, 2.0);
  Camera cam = lens;
  apply(path.frames[0], cam);
  const FrameStats lod_stats = render_frame(*lod, renderer, cam);
  const FrameStats brute_stats = render_frame(brute, renderer, cam);
  EXPECT_LT(lod_stats.triangles * 2, brute_stats.triangles);
}

TEST(LodBaseline, NamesAndWhatItNeeds) {
  EXPECT_EQ(parse_lod_strategy_name("lod").max_px, 1.0f);
  EXPECT_EQ(parse_lod_strategy_name("lod:px=0.5").max_px, 0.5f);
  EXPECT_THROW(check_strategy_name("lod:px=0"), Error);
  EXPECT_THROW(check_strategy_name("lod:pixels=1"), Error);
  EXPECT_FALSE(is_lod_strategy_name("vlod"));
  test::TempDir dir;
  const World world(test::write_street_world(dir, 4));
  try {
    make_strategy("lod", world, StrategyOptions{});
    FAIL() << "no image height";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("image height"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cellwalk
