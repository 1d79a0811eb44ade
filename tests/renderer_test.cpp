// Tests of the OpenGL renderer on the headless EGL context (llvmpipe): ids and depth, the
// subset property the fidelity harness relies on, the GPU budget, skipping, determinism, and
// PNG output.
#include "cellwalk/render/renderer.hpp"

#include <epoxy/gl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/core/process_memory.hpp"
#include "render/gpu_mesh_cache.hpp"
#include "render/text_overlay.hpp"
#include "test_support.hpp"

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

namespace cellwalk {
namespace {

constexpr int kWidth = 160;
constexpr int kHeight = 120;

// A box with flat-shaded faces (24 vertices, 12 triangles), optionally cut into n×n quads per
// face so meshes of different sizes can be made.
Mesh make_box(const Vec3& center, const Vec3& half, int n = 1) {
  Mesh mesh;
  for (int axis = 0; axis < 3; ++axis) {
    for (float sign : {-1.0f, 1.0f}) {
      Vec3 normal(0.0f);
      normal[axis] = sign;
      Vec3 u(0.0f), v(0.0f);
      u[(axis + 1) % 3] = 1.0f;
      v[(axis + 2) % 3] = 1.0f;
      uint32_t base = uint32_t(mesh.positions.size());
      for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
          Vec3 p = normal + u * (2.0f * i / n - 1.0f) + v * (2.0f * j / n - 1.0f);
          mesh.positions.push_back(center + p * half);
          mesh.normals.push_back(normal);
        }
      }
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          uint32_t a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
          mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
        }
      }
    }
  }
  return mesh;
}

// Looking down -Z from z = 10 at the origin.
Camera test_camera() {
  Camera camera;
  camera.position = Vec3(0.0f, 0.0f, 10.0f);
  camera.aspect = float(kWidth) / kHeight;
  camera.near_plane = 0.1f;
  camera.far_plane = 100.0f;
  return camera;
}

// Meshes by (object, lod), served by pointer as the renderer's provider expects.
class Meshes {
 public:
  void add(ObjectId object, Mesh mesh, uint32_t lod = 0) {
    meshes_[{object, lod}] = std::move(mesh);
  }
  MeshProvider provider() {
    return [this](const DrawItem& item) -> const Mesh* {
      ++calls_;
      auto it = meshes_.find({item.id, item.lod});
      return it == meshes_.end() ? nullptr : &it->second;
    };
  }
  int calls() const { return calls_; }

 private:
  std::map<std::pair<ObjectId, uint32_t>, Mesh> meshes_;
  int calls_ = 0;
};

uint32_t id_at(const IdImage& image, int x, int y) {
  return image.ids[size_t(y) * image.width + x];
}

class RendererTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { context_ = GlContext::headless(); }
  static void TearDownTestSuite() { context_.reset(); }

  static RenderSettings settings(uint64_t budget = 64ull << 20) {
    RenderSettings s;
    s.width = kWidth;
    s.height = kHeight;
    s.gpu_budget_bytes = budget;
    return s;
  }

  static inline std::unique_ptr<GlContext> context_;
};

TEST_F(RendererTest, ContextIsOpenGl45OnMesa) {
  EXPECT_FALSE(context_->renderer_name().empty());
}

TEST_F(RendererTest, BoxInFrontOfTheCameraFillsTheCentreWithItsId) {
  Meshes meshes;
  meshes.add(7, make_box(Vec3(0.0f), Vec3(1.0f)));
  Renderer renderer(settings());
  std::vector<DrawItem> items{{7, 0, rgba8(255, 0, 0)}};
  RenderStats stats = renderer.render(test_camera(), items, meshes.provider());

  IdImage ids = renderer.read_ids();
  EXPECT_EQ(id_at(ids, kWidth / 2, kHeight / 2), 8u);
  for (auto [x, y] :
       {std::pair{0, 0}, {kWidth - 1, 0}, {0, kHeight - 1}, {kWidth - 1, kHeight - 1}}) {
    EXPECT_EQ(id_at(ids, x, y), kBackgroundId);
  }
  Image color = renderer.read_color();
  const uint8_t* centre = &color.rgba[(size_t(kHeight / 2) * kWidth + kWidth / 2) * 4];
  EXPECT_GT(centre[0], 0);  // red, lit: the front face gets ambient plus some diffuse
  EXPECT_EQ(centre[1], 0);
  const uint8_t* corner = &color.rgba[0];
  RenderSettings s = settings();
  EXPECT_EQ(corner[0], s.background & 0xFF);
  EXPECT_EQ(corner[1], s.background >> 8 & 0xFF);
  EXPECT_EQ(stats.triangles, 12u);
  EXPECT_EQ(stats.objects, 1u);
  EXPECT_EQ(stats.gpu_misses, 1u);
  EXPECT_GT(stats.ms, 0.0);
}

TEST_F(RendererTest, NearerObjectWinsTheIdWhateverTheOrder) {
  Meshes meshes;
  meshes.add(1, make_box(Vec3(0.0f, 0.0f, 2.0f), Vec3(0.5f)));   // near
  meshes.add(2, make_box(Vec3(0.0f, 0.0f, -3.0f), Vec3(2.0f)));  // far, larger
  meshes.add(3, make_box(Vec3(0.0f, 0.0f, 4.0f), Vec3(0.2f)));   // nearest, small
  Renderer renderer(settings());
  for (std::vector<DrawItem> items : {std::vector<DrawItem>{{1}, {2}}, {{2}, {1}}}) {
    renderer.render(test_camera(), items, meshes.provider());
    EXPECT_EQ(id_at(renderer.read_ids(), kWidth / 2, kHeight / 2), 2u);
  }
  std::vector<DrawItem> all{{3}, {2}, {1}};
  renderer.render(test_camera(), all, meshes.provider());
  EXPECT_EQ(id_at(renderer.read_ids(), kWidth / 2, kHeight / 2), 4u);
}

// An object and an aggregate with the same id are different things: the GPU cache asks for
// each (a shared key would draw the object's mesh for the aggregate), and the aggregate's
// pixels carry its kind, so they never count as the object's.
TEST_F(RendererTest, KindsWithTheSameIdAreCachedAndIdentifiedApart) {
  const Mesh small = make_box(Vec3(0.0f), Vec3(0.5f));
  const Mesh large = make_box(Vec3(0.0f, 0.0f, -5.0f), Vec3(3.0f, 3.0f, 1.0f));  // behind it, wider
  const DrawItem object{5, 0, rgba8(255, 0, 0)};
  const DrawItem aggregate{5, 0, rgba8(0, 255, 0), DrawKind::kAggregate};
  int asked_object = 0, asked_aggregate = 0;
  const MeshProvider provider = [&](const DrawItem& item) -> const Mesh* {
    if (item.kind == DrawKind::kObject) return ++asked_object, &small;
    return ++asked_aggregate, &large;
  };
  Renderer renderer(settings());
  for (int frame = 0; frame < 2; ++frame) renderer.render(test_camera(), std::vector{object, aggregate}, provider);
  EXPECT_EQ(asked_object, 1);
  EXPECT_EQ(asked_aggregate, 1);
  const IdImage ids = renderer.read_ids();
  EXPECT_EQ(id_at(ids, kWidth / 2, kHeight / 2), pixel_id(object));
  EXPECT_EQ(pixel_id(object), 6u);
  EXPECT_NE(pixel_id(aggregate), pixel_id(object));
  EXPECT_EQ(id_at(ids, kWidth / 2 + kWidth / 8, kHeight / 2), pixel_id(aggregate));
}

// Random overlapping boxes of various tessellations, ids 0..count-1.
Meshes random_scene(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> position(-4.0f, 4.0f), size(0.3f, 1.5f);
  std::uniform_int_distribution<int> tessellation(1, 6);
  Meshes meshes;
  for (int i = 0; i < count; ++i) {
    Vec3 center(position(rng), position(rng) * 0.7f, position(rng));
    meshes.add(ObjectId(i),
               make_box(center, Vec3(size(rng), size(rng), size(rng)), tessellation(rng)));
  }
  return meshes;
}

std::vector<DrawItem> items_for(int count) {
  std::vector<DrawItem> items;
  for (int i = 0; i < count; ++i) {
    items.push_back({ObjectId(i), 0, rgba8(uint8_t(40 + 7 * i), uint8_t(200 - 5 * i), 90)});
  }
  return items;
}

TEST_F(RendererTest, SubsetRendersItsObjectsPixelsExactlyAsTheFullList) {
  constexpr int kCount = 24;
  Meshes meshes = random_scene(kCount, 11);
  Renderer renderer(settings());
  std::vector<DrawItem> full = items_for(kCount);
  renderer.render(test_camera(), full, meshes.provider());
  Image full_color = renderer.read_color();
  IdImage full_ids = renderer.read_ids();

  std::vector<DrawItem> subset;
  std::set<uint32_t> subset_ids;
  for (int i = kCount - 1; i >= 0; i -= 2) {  // every other object, in reverse order
    subset.push_back(full[i]);
    subset_ids.insert(pixel_id(full[i]));
  }
  renderer.render(test_camera(), subset, meshes.provider());
  Image color = renderer.read_color();
  IdImage ids = renderer.read_ids();

  int compared = 0;
  for (size_t p = 0; p < full_ids.ids.size(); ++p) {
    if (!subset_ids.count(full_ids.ids[p])) continue;
    ++compared;
    ASSERT_EQ(ids.ids[p], full_ids.ids[p]) << "pixel " << p;
    ASSERT_EQ(std::memcmp(&color.rgba[p * 4], &full_color.rgba[p * 4], 4), 0) << "pixel " << p;
  }
  EXPECT_GT(compared, 1000);
}

TEST_F(RendererTest, TinyBudgetIsNeverExceededAndRendersTheSameImage) {
  constexpr int kCount = 40;
  Meshes meshes = random_scene(kCount, 5);
  std::vector<DrawItem> items = items_for(kCount);
  Renderer unbounded(settings());
  unbounded.render(test_camera(), items, meshes.provider());
  Image expected_color = unbounded.read_color();
  IdImage expected_ids = unbounded.read_ids();

  // Room for a few of the meshes only: every frame evicts, some meshes exceed it entirely.
  const uint64_t budget = 8 * 1024;
  Renderer bounded(settings(budget));
  for (int frame = 0; frame < 3; ++frame) {
    RenderStats stats = bounded.render(test_camera(), items, meshes.provider());
    EXPECT_LE(stats.gpu_resident_bytes, budget);
    EXPECT_GT(stats.gpu_misses, 0u);
    EXPECT_GT(stats.uploaded_bytes, budget);
    EXPECT_EQ(bounded.read_color().rgba, expected_color.rgba);
    EXPECT_EQ(bounded.read_ids().ids, expected_ids.ids);
  }
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  if (const char* dir = std::getenv("CELLWALK_TEST_IMAGES")) {
    write_png(expected_color, std::string(dir) + "/renderer_random_scene.png");
  }
}

TEST_F(RendererTest, CacheStaysUnderBudgetAndEvictsLeastRecentlyUsed) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> tessellation(1, 8);
  const uint64_t budget = 40 * 1024;
  render::GpuMeshCache cache(budget);
  std::map<ObjectId, Mesh> meshes;
  for (ObjectId id = 0; id < 200; ++id) {
    Mesh mesh = make_box(Vec3(0.0f), Vec3(1.0f), tessellation(rng));
    ASSERT_LE(render::GpuMesh::bytes_for(mesh), budget);
    render::MeshKey key{id % 50, id / 50};
    if (cache.find(key) == nullptr) cache.insert(key, mesh);
    ASSERT_LE(cache.resident_bytes(), budget);
    // Evicted buffers may still be read by queued draws: they count until the GPU finishes.
    ASSERT_LE(cache.held_bytes(), budget);
  }
  // Recently inserted keys are resident; keeping one in use protects it from eviction.
  render::MeshKey kept{49, 3};
  ASSERT_NE(cache.find(kept), nullptr);
  for (ObjectId id = 1000; id < 1040; ++id) {
    cache.insert({id, 0}, make_box(Vec3(0.0f), Vec3(1.0f), 2));
    ASSERT_NE(cache.find(kept), nullptr);
    ASSERT_LE(cache.resident_bytes(), budget);
  }
  EXPECT_EQ(cache.find({0, 0}), nullptr);
  cache.gpu_finished();
  EXPECT_EQ(cache.held_bytes(), cache.resident_bytes());
}

// A mesh of more than two driver batches is drawn in index ranges with waits between them:
// every triangle still lands, so its ids are exactly those of the same box in 12 triangles.
TEST_F(RendererTest, MeshOfSeveralDriverBatchesDrawsEveryTriangle) {
  const int n = 105;  // 6 faces × 2n² = 132,300 triangles
  ASSERT_GT(12u * n * n, 2 * kDriverBatchTriangles);
  Meshes meshes;
  meshes.add(1, make_box(Vec3(0.0f), Vec3(2.0f, 1.5f, 1.0f), n));
  meshes.add(2, make_box(Vec3(0.0f), Vec3(2.0f, 1.5f, 1.0f)));
  Renderer renderer(settings());
  Camera camera = test_camera();
  camera.position = Vec3(1.0f, 0.7f, 6.0f);  // off axis: several faces show
  const RenderStats fine = renderer.render(camera, std::vector<DrawItem>{{1}}, meshes.provider());
  const IdImage tessellated = renderer.read_ids();
  renderer.render(camera, std::vector<DrawItem>{{2}}, meshes.provider());
  const IdImage whole = renderer.read_ids();
  EXPECT_EQ(fine.triangles, 12u * n * n);
  size_t covered = 0, differ = 0;
  for (size_t i = 0; i < whole.ids.size(); ++i) {
    covered += whole.ids[i] != kBackgroundId;
    differ += (whole.ids[i] != kBackgroundId) != (tessellated.ids[i] != kBackgroundId);
  }
  EXPECT_GT(covered, whole.ids.size() / 10);
  EXPECT_EQ(differ, 0u);
}

// llvmpipe keeps the memory it bins triangles into; without a wait every driver batch, a frame
// of two million long thin triangles grew the process by about 480 MiB at 640 × 480.
TEST_F(RendererTest, DriverMemoryDoesNotGrowWithTheTrianglesOfAFrame) {
  if (test::kUnderAddressSanitizer) GTEST_SKIP() << "ASan's quarantine keeps freed memory resident";
  Mesh fan;
  fan.positions.push_back(Vec3(0.0f));
  const uint32_t spokes = 1u << 16;
  for (uint32_t i = 0; i <= spokes; ++i) {
    const float a = 6.2831853f * float(i) / float(spokes);
    fan.positions.push_back(Vec3(20.0f * std::cos(a), 20.0f * std::sin(a), 0.0f));
  }
  for (uint32_t i = 1; i <= spokes; ++i) fan.indices.insert(fan.indices.end(), {0u, i, i + 1});
  Meshes meshes;
  meshes.add(1, fan);
  std::vector<DrawItem> items;
  for (uint32_t copy = 0; copy < 32; ++copy) items.push_back({1});
  RenderSettings s = settings();
  s.width = 640;
  s.height = 480;
  Renderer renderer(s);
  renderer.render(test_camera(), std::vector<DrawItem>{{1}}, meshes.provider());  // shaders, one batch
  const uint64_t before = current_rss_bytes();
  const RenderStats stats = renderer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(stats.triangles, 32u * spokes);
  EXPECT_LT(current_rss_bytes(), before + (48ull << 20)) << "the driver's memory grew with the frame";
}

TEST_F(RendererTest, MeshLargerThanTheBudgetIsDrawnButNotKept) {
  Meshes meshes;
  meshes.add(0, make_box(Vec3(0.0f), Vec3(1.0f), 8));
  std::vector<DrawItem> items{{0}};
  Renderer renderer(settings(1024));
  RenderStats stats = renderer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(stats.gpu_resident_bytes, 0u);
  EXPECT_EQ(stats.triangles, 6u * 8 * 8 * 2);
  EXPECT_EQ(id_at(renderer.read_ids(), kWidth / 2, kHeight / 2), 1u);
  stats = renderer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(stats.gpu_misses, 1u);
}

// A transient item's mesh changes between frames under one key: each frame draws the mesh it
// is given now, and none is kept (a view-dependent client would fill the cache with stale
// copies, one per frame).
TEST_F(RendererTest, TransientItemIsDrawnAsGivenEachFrameAndNeverKept) {
  Meshes meshes;
  meshes.add(0, make_box(Vec3(0.0f), Vec3(1.0f)));
  std::vector<DrawItem> items{{0, 0, rgba8(200, 200, 200), DrawKind::kObject, true}};
  Renderer renderer(settings());
  RenderStats stats = renderer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(stats.gpu_resident_bytes, 0u);
  EXPECT_EQ(id_at(renderer.read_ids(), kWidth / 2, kHeight / 2), 1u);
  meshes.add(0, make_box(Vec3(3.0f, 0.0f, 0.0f), Vec3(0.5f)));  // moved off the centre
  stats = renderer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(stats.gpu_misses, 1u);
  EXPECT_EQ(stats.gpu_resident_bytes, 0u);
  EXPECT_EQ(id_at(renderer.read_ids(), kWidth / 2, kHeight / 2), 0u) << "the first frame's mesh was drawn again";
}

// An object whose level has no triangles (every piece culled) is drawn as nothing, and its
// neighbours as ever. Under the sanitizers this caught a copy from a null index array.
TEST_F(RendererTest, EmptyMeshDrawsNothingAndLeavesTheOthersAlone) {
  Meshes meshes;
  meshes.add(0, Mesh{});
  meshes.add(1, make_box(Vec3(0.0f), Vec3(1.0f)));
  std::vector<DrawItem> items{{0}, {1}};
  Renderer renderer(settings());
  RenderStats stats = renderer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(stats.triangles, 12u);
  IdImage ids = renderer.read_ids();
  EXPECT_EQ(std::count(ids.ids.begin(), ids.ids.end(), 1u), 0);
  EXPECT_EQ(id_at(ids, kWidth / 2, kHeight / 2), 2u);
}

TEST_F(RendererTest, ProviderReturningNullSkipsTheItemUntilItsDataIsReady) {
  Meshes meshes;
  meshes.add(1, make_box(Vec3(-2.0f, 0.0f, 0.0f), Vec3(1.0f)));
  Mesh late = make_box(Vec3(2.0f, 0.0f, 0.0f), Vec3(1.0f));
  std::vector<DrawItem> items{{1}, {2}};
  Renderer renderer(settings());
  RenderStats stats = renderer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(stats.objects, 1u);
  EXPECT_EQ(stats.triangles, 12u);
  IdImage ids = renderer.read_ids();
  EXPECT_EQ(std::count(ids.ids.begin(), ids.ids.end(), 3u), 0);
  EXPECT_GT(std::count(ids.ids.begin(), ids.ids.end(), 2u), 0);

  meshes.add(2, late);  // the data arrives: the next frame draws it
  stats = renderer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(stats.objects, 2u);
  EXPECT_EQ(stats.gpu_hits, 1u);
  EXPECT_EQ(stats.gpu_misses, 1u);
  ids = renderer.read_ids();
  EXPECT_GT(std::count(ids.ids.begin(), ids.ids.end(), 3u), 0);
}

TEST_F(RendererTest, RenderingIsDeterministic) {
  Meshes meshes = random_scene(16, 9);
  std::vector<DrawItem> items = items_for(16);
  Renderer first(settings());
  first.render(test_camera(), items, meshes.provider());
  Image color = first.read_color();
  IdImage ids = first.read_ids();
  first.render(test_camera(), items, meshes.provider());  // from the cache this time
  EXPECT_EQ(first.read_color().rgba, color.rgba);
  EXPECT_EQ(first.read_ids().ids, ids.ids);
  Renderer second(settings());
  second.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(second.read_color().rgba, color.rgba);
  EXPECT_EQ(second.read_ids().ids, ids.ids);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

size_t changed_pixels(const Image& a, const Image& b, int x0, int y0, int x1, int y1) {
  size_t changed = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      size_t p = (size_t(y) * a.width + x) * 4;
      changed += std::memcmp(&a.rgba[p], &b.rgba[p], 4) != 0;
    }
  }
  return changed;
}

TEST_F(RendererTest, AnInnerContextGivesTheOuterOneBackWhenDestroyed) {
  // A far-field baker makes its own context inside a walk or a test; when it goes, the
  // renderers of the context around it must draw again.
  Meshes meshes = random_scene(16, 9);
  const std::vector<DrawItem> items = items_for(16);
  Renderer outer(settings());
  outer.render(test_camera(), items, meshes.provider());
  const Image expected = outer.read_color();
  {
    const std::unique_ptr<GlContext> inner = GlContext::headless();
    Renderer renderer(settings());
    renderer.render(test_camera(), items, meshes.provider());
    EXPECT_EQ(renderer.read_color().rgba, expected.rgba);
  }
  EXPECT_FALSE(context_->renderer_name().empty());
  outer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(outer.read_color().rgba, expected.rgba);
}

TEST_F(RendererTest, LinesAreDrawnOverTheImageAndLeaveIdsAlone) {
  Meshes meshes;
  meshes.add(0, make_box(Vec3(0.0f), Vec3(1.0f)));
  std::vector<DrawItem> items{{0}};
  Renderer renderer(settings());
  renderer.render(test_camera(), items, meshes.provider());
  Image before = renderer.read_color();
  IdImage ids = renderer.read_ids();
  // A horizontal line through the centre, in front of and beyond the box.
  std::vector<LineSegment> segments{
      {Vec3(-20.0f, 0.0f, 0.0f), Vec3(20.0f, 0.0f, 0.0f), rgba8(255, 0, 255)}};
  renderer.draw_lines(test_camera(), segments);
  Image after = renderer.read_color();
  EXPECT_EQ(renderer.read_ids().ids, ids.ids);
  int centre_row = kHeight / 2;
  EXPECT_GT(changed_pixels(before, after, 0, centre_row - 1, kWidth, centre_row + 1),
            size_t(kWidth) * 9 / 10);
  EXPECT_EQ(changed_pixels(before, after, 0, 0, kWidth, centre_row - 2), 0u);
  EXPECT_EQ(changed_pixels(before, after, 0, centre_row + 2, kWidth, kHeight), 0u);
  // The next frame starts clean.
  renderer.render(test_camera(), items, meshes.provider());
  EXPECT_EQ(renderer.read_color().rgba, before.rgba);
}

TEST_F(RendererTest, TextIsDrawnAtItsTopLeftCorner) {
  std::vector<DrawItem> none;
  Renderer renderer(settings());
  renderer.render(test_camera(), none, Meshes().provider());
  Image before = renderer.read_color();
  renderer.draw_text(10.0f, 20.0f, "cellwalk 42", rgba8(255, 255, 255), 2.0f);
  Image after = renderer.read_color();
  // Image rows are bottom-up: text 20..~36 px from the top is in rows height-36..height-20.
  int top = kHeight - 20, bottom = kHeight - 20 - 2 * 12;
  EXPECT_GT(changed_pixels(before, after, 10, bottom, kWidth, top), 100u);
  EXPECT_EQ(changed_pixels(before, after, 0, 0, kWidth, bottom), 0u);
  EXPECT_EQ(changed_pixels(before, after, 0, top, kWidth, kHeight), 0u);
  EXPECT_EQ(changed_pixels(before, after, 0, 0, 10, kHeight), 0u);
}

// Issue 16: the viewer's statistics ran off the window and were unreadable over a city. Text
// now wraps at spaces inside the image and can lie on an opaque panel.
TEST_F(RendererTest, LongTextWrapsInsideTheImageOnItsPanel) {
  std::vector<DrawItem> none;
  Renderer renderer(settings());
  renderer.render(test_camera(), none, Meshes().provider());
  const Image before = renderer.read_color();
  const std::string text = "one two three four five six seven eight nine ten eleven twelve thirteen fourteen";
  ASSERT_GT(render::text_size(text, 1.0f).x, float(kWidth)) << "the text must be wider than the image";
  const Rgba8 panel = rgba8(10, 20, 30);
  renderer.draw_text(4.0f, 4.0f, text, rgba8(255, 255, 255), 1.0f, panel);
  const Image after = renderer.read_color();
  const std::string wrapped = render::wrap_text(text, float(kWidth) - 8.0f, 1.0f);
  const size_t lines = size_t(std::count(wrapped.begin(), wrapped.end(), '\n')) + 1;
  EXPECT_GE(lines, 2u);
  for (size_t start = 0; start < wrapped.size();) {
    const size_t end = std::min(wrapped.find('\n', start), wrapped.size());
    EXPECT_LE(render::text_size(wrapped.substr(start, end - start), 1.0f).x, float(kWidth) - 8.0f);
    start = end + 1;
  }
  // Every word is kept, in order.
  std::string joined = wrapped;
  std::replace(joined.begin(), joined.end(), '\n', ' ');
  EXPECT_EQ(joined, text);
  // The panel covers the wrapped text's height (several lines) with its colour at the corners.
  const auto pixel = [&after](int x, int y_from_top) {
    const uint8_t* p = &after.rgba[(size_t(after.height - 1 - y_from_top) * after.width + x) * 4];
    return rgba8(p[0], p[1], p[2]);
  };
  const int panel_bottom = int(4 + render::text_size(wrapped, 1.0f).y + 4);
  EXPECT_EQ(pixel(1, 1), panel);
  EXPECT_EQ(pixel(1, panel_bottom - 2), panel) << "the panel spans every line";
  EXPECT_EQ(changed_pixels(before, after, 0, 0, kWidth, after.height - panel_bottom - 1), 0u) << "nothing below the panel";
}

// A 3×2 image whose bottom row (stored first) is red and top row blue.
Image two_row_image() {
  Image image{3, 2, {}};
  for (int i = 0; i < 3; ++i) image.rgba.insert(image.rgba.end(), {255, 0, 0, 255});
  for (int i = 0; i < 3; ++i) image.rgba.insert(image.rgba.end(), {0, 0, 255, 255});
  return image;
}

std::string read_bytes(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

uint32_t big_endian(const std::string& bytes, size_t offset) {
  return uint32_t(uint8_t(bytes[offset])) << 24 | uint32_t(uint8_t(bytes[offset + 1])) << 16 |
         uint32_t(uint8_t(bytes[offset + 2])) << 8 | uint8_t(bytes[offset + 3]);
}

// A 4×4 far-face image: left half red, right half blue, its top row empty (alpha 0).
Image far_image() {
  Image image{4, 4, std::vector<uint8_t>(64, 0)};
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      uint8_t* p = &image.rgba[(size_t(y) * 4 + x) * 4];
      p[x < 2 ? 0 : 2] = 255;
      p[3] = 255;
    }
  return image;
}

// The quad z = -5, x in [-4, 4], y in [-3, 3], in front of test_camera().
FarFace far_face(uint32_t id, const Image& image, const IdImage* ids = nullptr) {
  return {id, Vec3(-4.0f, -3.0f, -5.0f), Vec3(8.0f, 0.0f, 0.0f), Vec3(0.0f, 6.0f, 0.0f), &image, ids};
}

// Where the world point p lands in the image (pixel column, row from the bottom).
std::pair<int, int> pixel_of(const Vec3& p) {
  const Vec4 clip = test_camera().view_projection() * Vec4(p, 1.0f);
  return {int((clip.x / clip.w * 0.5f + 0.5f) * kWidth), int((clip.y / clip.w * 0.5f + 0.5f) * kHeight)};
}

TEST_F(RendererTest, FarFaceShowsItsImageAndLetsEmptyTexelsThrough) {
  Renderer renderer(settings());
  const Image image = far_image();
  const std::vector<FarFace> faces{far_face(3, image)};
  Meshes meshes;
  const RenderStats stats = renderer.render(test_camera(), {}, meshes.provider(), faces);
  EXPECT_EQ(stats.uploaded_bytes, 64u);
  const Image color = renderer.read_color();
  const IdImage ids = renderer.read_ids();
  auto rgba = [&](const Vec3& p) {
    const auto [x, y] = pixel_of(p);
    return &color.rgba[(size_t(y) * kWidth + x) * 4];
  };
  EXPECT_GT(rgba(Vec3(-2.5f, -1.0f, -5.0f))[0], 200);  // left: red
  EXPECT_LT(rgba(Vec3(-2.5f, -1.0f, -5.0f))[2], 50);
  EXPECT_GT(rgba(Vec3(2.5f, -1.0f, -5.0f))[2], 200);   // right: blue
  const RenderSettings s = settings();
  EXPECT_EQ(rgba(Vec3(-2.5f, 2.7f, -5.0f))[0], s.background & 0xFF);  // top row: empty, background
  const auto [fx, fy] = pixel_of(Vec3(-2.5f, -1.0f, -5.0f));
  EXPECT_EQ(id_at(ids, fx, fy), pixel_id({3, 0, 0, DrawKind::kFarFace}));
  const auto [ex, ey] = pixel_of(Vec3(-2.5f, 2.7f, -5.0f));
  EXPECT_EQ(id_at(ids, ex, ey), kBackgroundId);
  // Drawn again, the texture is resident: nothing uploaded.
  EXPECT_EQ(renderer.render(test_camera(), {}, meshes.provider(), faces).uploaded_bytes, 0u);
}

TEST_F(RendererTest, FarFaceIsBackgroundToNearGeometryEvenBehindIt) {
  // Near objects may stick out past their box (digest 002 §3.6): one behind the face still
  // covers it, because far faces write no depth.
  Meshes meshes;
  meshes.add(5, make_box(Vec3(0.0f, -1.0f, -8.0f), Vec3(0.5f)));
  const Image image = far_image();
  IdImage object_ids{4, 4, std::vector<uint32_t>(16, 42)};
  const std::vector<FarFace> faces{far_face(3, image, &object_ids)};
  Renderer renderer(settings());
  std::vector<DrawItem> items{{5, 0, rgba8(0, 255, 0)}};
  renderer.render(test_camera(), items, meshes.provider(), faces);
  const IdImage ids = renderer.read_ids();
  const auto [bx, by] = pixel_of(Vec3(0.0f, -1.0f, -7.5f));
  EXPECT_EQ(id_at(ids, bx, by), 6u);
  // Elsewhere on the face, its id image: the object the texel shows.
  const auto [fx, fy] = pixel_of(Vec3(-3.0f, -2.0f, -5.0f));
  EXPECT_EQ(id_at(ids, fx, fy), 42u);
}

TEST_F(RendererTest, FarFaceTexturesStayUnderTheirBudget) {
  RenderSettings s = settings();
  s.far_face_budget_bytes = 100;  // one 4×4 colour image (64 bytes) at a time
  Renderer renderer(s);
  const Image image = far_image();
  Meshes meshes;
  for (uint32_t id = 0; id < 3; ++id) {
    const std::vector<FarFace> faces{far_face(id, image)};
    const RenderStats stats = renderer.render(test_camera(), {}, meshes.provider(), faces);
    EXPECT_EQ(stats.uploaded_bytes, 64u);
    EXPECT_LE(stats.gpu_resident_bytes, 100u);
  }
  IdImage ids{4, 4, std::vector<uint32_t>(16, 1)};
  const std::vector<FarFace> too_large{far_face(9, image, &ids)};  // 128 bytes
  EXPECT_THROW(renderer.render(test_camera(), {}, meshes.provider(), too_large), Error);
  IdImage wrong{2, 2, std::vector<uint32_t>(4, 1)};
  const std::vector<FarFace> mismatched{far_face(10, image, &wrong)};
  s.far_face_budget_bytes = 1 << 20;
  Renderer roomy(s);
  EXPECT_THROW(roomy.render(test_camera(), {}, meshes.provider(), mismatched), Error);
}

// Issue 16: the backdrop's ground was at y = 0 whatever the world, so below it the view showed
// sky above and below. Fitted to a world whose floor is at y = -181, a camera just above that
// floor looking down sees ground; one below it sees sky.
TEST_F(RendererTest, BackdropGroundLiesAtTheWorldsFloor) {
  RenderSettings s = settings();
  s.backdrop = true;
  fit_backdrop(s, Aabb{{-370, -181, -200}, {370, 150, 200}});
  EXPECT_EQ(s.ground_y, -181.0f);
  EXPECT_EQ(s.ground_grid, 10.0f);
  Renderer renderer(s);
  Meshes none;
  const auto centre_is_ground = [&](float eye_y) {
    Camera cam = test_camera();
    cam.position = Vec3(0, eye_y, 0);
    cam.pitch_deg = -60;
    renderer.render(cam, {}, none.provider());
    const Image color = renderer.read_color();
    const uint8_t* c = &color.rgba[(size_t(kHeight / 2) * kWidth + kWidth / 2) * 4];
    return c[2] < c[1] + 10;  // earth is grey-green; the sky is blue
  };
  EXPECT_TRUE(centre_is_ground(-179.3f));
  EXPECT_FALSE(centre_is_ground(-182.0f));
  RenderSettings scan;
  fit_backdrop(scan, Aabb{{-0.5f, 0, -0.5f}, {0.5f, 1, 0.5f}});
  EXPECT_FLOAT_EQ(scan.ground_grid, 0.1f);
}

// A quad in the plane z = 0 facing the test camera, x in [x0, x1], y in [y0, y1], with uvs
// (0, 0) at its top-left corner and (1, 1) at its bottom-right when it samples `texture`.
Mesh facing_quad(float x0, float x1, float y0, float y1, uint32_t texture = kNoTexture) {
  Mesh m;
  m.positions = {{x0, y1, 0}, {x1, y1, 0}, {x0, y0, 0}, {x1, y0, 0}};
  m.normals.assign(4, Vec3(0, 0, 1));
  m.indices = {0, 2, 1, 1, 2, 3};
  if (texture != kNoTexture) {
    m.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    m.texture = texture;
  }
  return m;
}

// 4 × 4 blocks of 2 × 2 texels, each block its own colour: linear filtering at a block's centre
// mixes only texels of that block, so the colour there is exact.
constexpr int kBlocks = 4;
Rgba8 block_color(int column, int row) {
  return rgba8(uint8_t(40 + 60 * column), uint8_t(30 + 70 * row), uint8_t(200 - 40 * (column + row)));
}
Texture block_texture() {
  Texture t;
  t.width = t.height = 2 * kBlocks;
  for (uint32_t y = 0; y < t.height; ++y)
    for (uint32_t x = 0; x < t.width; ++x) t.texels.push_back(block_color(int(x / 2), int(y / 2)));
  return t;
}

// The reference a textured render is compared with: each block drawn as an untextured quad of
// its colour, where the texture would put it.
TEST_F(RendererTest, TexturedQuadMatchesItsUntexturedReference) {
  constexpr float kX0 = -4, kX1 = 4, kY0 = -3, kY1 = 3;
  Meshes textured, reference;
  textured.add(0, facing_quad(kX0, kX1, kY0, kY1, 5));
  std::vector<DrawItem> reference_items;
  const float bw = (kX1 - kX0) / kBlocks, bh = (kY1 - kY0) / kBlocks;
  for (int row = 0; row < kBlocks; ++row)
    for (int column = 0; column < kBlocks; ++column) {
      const uint32_t id = uint32_t(1 + row * kBlocks + column);  // 0 is the textured quad, held by the cache
      reference.add(id, facing_quad(kX0 + bw * column, kX0 + bw * (column + 1), kY1 - bh * (row + 1), kY1 - bh * row));
      reference_items.push_back({id, 0, block_color(column, row)});
    }
  Renderer renderer(settings());
  std::vector<uint32_t> asked;
  renderer.set_texture_source([&](uint32_t index, uint32_t) -> std::optional<Texture> {
    asked.push_back(index);
    return block_texture();
  });
  const std::vector<DrawItem> items{{0, 0, rgba8(255, 255, 255)}};
  for (int frame = 0; frame < 2; ++frame) renderer.render(test_camera(), items, textured.provider());
  EXPECT_EQ(asked, std::vector<uint32_t>{5}) << "asked once, then held";
  const Image got = renderer.read_color();
  renderer.render(test_camera(), reference_items, reference.provider());
  const Image want = renderer.read_color();
  // The blocks' centres, projected: the camera looks down -z from z = 10 with a 60° fov.
  const float half_height = 10.0f * std::tan(glm::radians(30.0f)), half_width = half_height * kWidth / kHeight;
  int compared = 0;
  for (int row = 0; row < kBlocks; ++row)
    for (int column = 0; column < kBlocks; ++column) {
      const float cx = kX0 + bw * (column + 0.5f), cy = kY1 - bh * (row + 0.5f);
      const int px = int((cx / half_width * 0.5f + 0.5f) * kWidth), py = int((cy / half_height * 0.5f + 0.5f) * kHeight);
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const size_t at = (size_t(py + dy) * kWidth + size_t(px + dx)) * 4;
          for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(got.rgba[at + c], want.rgba[at + c], 1) << "block " << column << "," << row << " channel " << c;
          ++compared;
        }
    }
  EXPECT_EQ(compared, kBlocks * kBlocks * 9);
  // Without a source the same mesh is drawn in its colour alone.
  Renderer plain(settings());
  plain.render(test_camera(), items, textured.provider());
  const Image flat = plain.read_color();
  const size_t centre = (size_t(kHeight / 2) * kWidth + kWidth / 2) * 4;
  EXPECT_EQ(flat.rgba[centre], flat.rgba[centre + 1]);
  EXPECT_EQ(flat.rgba[centre + 1], flat.rgba[centre + 2]);
}

// Textures take their share of the GPU budget, and a source is asked for textures whose fetch
// and upload need at most half that share, so meshes and textures together stay within
// gpu_budget_bytes.
TEST_F(RendererTest, TexturesStayWithinTheirShareOfTheGpuBudget) {
  const uint64_t budget = 256 << 10;  // textures: a quarter, 64 KiB
  Renderer renderer(settings(budget));
  std::vector<uint32_t> sides;
  renderer.set_texture_source([&](uint32_t, uint32_t max_side) -> std::optional<Texture> {
    sides.push_back(max_side);
    Texture t;
    t.width = t.height = max_side;
    t.texels.assign(size_t(max_side) * max_side, rgba8(200, 100, 50));
    return t;
  });
  Meshes meshes;
  std::vector<DrawItem> items;
  for (uint32_t i = 0; i < 16; ++i) {
    meshes.add(i, facing_quad(-4.0f + 0.5f * i, -3.5f + 0.5f * i, -1, 1, i));
    items.push_back({i, 0});
  }
  for (int frame = 0; frame < 3; ++frame) {
    const RenderStats stats = renderer.render(test_camera(), items, meshes.provider());
    EXPECT_LE(stats.gpu_resident_bytes, budget);
  }
  ASSERT_FALSE(sides.empty());
  // The largest power of two whose texture (4/3 · 4 B a texel with its mipmaps) and fetch (its
  // encoded and decoded texels, 4 B a texel each) take at most 32 KiB: 32 (13.7 KiB; 64: 54.6 KiB).
  for (uint32_t side : sides) EXPECT_EQ(side, 32u);
  EXPECT_GT(sides.size(), 16u) << "sixteen textures of 5.3 KiB each do not fit in 64 KiB: some are fetched again";
}

TEST(WritePng, WritesAValidTopDownPng) {
  test::TempDir dir;
  std::string file = dir.file("out.png");
  write_png(two_row_image(), file);
  std::string bytes = read_bytes(file);
  ASSERT_GE(bytes.size(), 33u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(bytes.substr(12, 4), "IHDR");
  EXPECT_EQ(big_endian(bytes, 16), 3u);
  EXPECT_EQ(big_endian(bytes, 20), 2u);

  int w = 0, h = 0, channels = 0;
  stbi_uc* pixels = stbi_load(file.c_str(), &w, &h, &channels, 4);
  ASSERT_NE(pixels, nullptr);
  EXPECT_EQ(pixels[2], 255);              // first decoded row is the top: blue
  EXPECT_EQ(pixels[3 * 4 * 1 + 0], 255);  // second row: red
  stbi_image_free(pixels);
}

TEST(WritePng, FailureNamesTheFileAndKeepsTheOldOne) {
  test::TempDir dir;
  std::string missing = dir.file("no-such-folder/out.png");
  try {
    write_png(two_row_image(), missing);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }

  std::string file = dir.file("kept.png");
  write_png(two_row_image(), file);
  std::string before = read_bytes(file);
  // A directory where the temporary would go makes the write fail even for root.
  std::filesystem::create_directory(temporary_path(file, ::getpid()));
  Image other = two_row_image();
  other.rgba[0] = 7;
  try {
    write_png(other, file);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_bytes(file), before);
  Image broken{4, 4, {1, 2, 3}};
  EXPECT_THROW(write_png(broken, file), Error);
  EXPECT_EQ(read_bytes(file), before);
}

}  // namespace
}  // namespace cellwalk

namespace cellwalk {
namespace {

// Run only from the test below, in a fresh process: makes the first headless context of the
// process with the rasteriser CELLWALK_TEST_RASTERISER names and prints the thread count.
TEST(GlContextThreads, DISABLED_CountThreadsAfterTheFirstContext) {
  const char* mode = std::getenv("CELLWALK_TEST_RASTERISER");
  ASSERT_NE(mode, nullptr);
  auto context = GlContext::headless(std::string(mode) == "calling" ? Rasteriser::kCallingThread : Rasteriser::kWorkerThreads);
  size_t threads = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator("/proc/self/task")) ++threads;
  std::printf("threads %zu\n", threads);
}

size_t threads_with(const std::string& mode) {
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  const std::string command = "env -u LP_NUM_THREADS CELLWALK_TEST_RASTERISER=" + mode + " EGL_PLATFORM=surfaceless '" + self +
                              "' --gtest_also_run_disabled_tests --gtest_filter=GlContextThreads.DISABLED_CountThreadsAfterTheFirstContext 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  EXPECT_NE(pipe, nullptr);
  if (!pipe) return 0;
  char line[512];
  size_t threads = 0;
  while (std::fgets(line, sizeof line, pipe)) std::sscanf(line, "threads %zu", &threads);
  EXPECT_EQ(pclose(pipe), 0);
  return threads;
}

// A budgeted walk's context rasterises on the calling thread: llvmpipe starts no rasteriser
// threads (docs/design.md, Memory: their bins made the process's peak vary by up to 18 MiB
// under CPU load).
TEST(GlContextThreads, CallingThreadRasteriserStartsNoWorkers) {
  const size_t workers = threads_with("workers"), calling = threads_with("calling");
  ASSERT_GT(calling, 0u);
  EXPECT_LT(calling, workers) << "llvmpipe started the same threads with LP_NUM_THREADS=0";
  std::printf("threads after the first context: %zu with worker rasterisers, %zu on the calling thread\n", workers, calling);
}

}  // namespace
}  // namespace cellwalk
