// Stratified rendering end to end (seed 002 §3.1.2, §3.2): a small random city (Appendix A)
// through `cellwalk stratify build`, its stored near lists and far faces read back, and the
// `stratified` strategy checked against brute force on the same frames.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/render/renderer.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/bake_pool.hpp"
#include "cellwalk/systems/stratified/far_field.hpp"
#include "cellwalk/systems/stratified/sizing.hpp"
#include "cellwalk/systems/stratified/stored_stratified.hpp"
#include "cellwalk/systems/stratified/stratified_strategy.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using namespace stratified;

constexpr int kResolution = 64;
constexpr float kBox = 120.0f;

// One city for the suite: 4 × 4 blocks (about 400 m square), stratified at α = 10°, b = 120 m.
class StratifiedSystem : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    inputs_ = new test::SharedInputs(
        "stratified-city", {"generate stratified-city --blocks-x 4 --blocks-z 4 --seed 5 -o {dir}/city.cwscene",
                            "build {dir}/city.cwscene -o {dir}/city.cww",
                            "stratify build {dir}/city.cww --alpha 10 --box 120 --resolution 64",
                            "path {dir}/city.cww -o {dir}/fast.path --frames 120 --kind fast --seed 3"});
    world_file_ = inputs_->file("city.cww");
    world_ = new World(world_file_);
    context_ = GlContext::headless().release();
  }
  static void TearDownTestSuite() {
    delete context_;
    delete world_;
    delete inputs_;
  }
  // A fast path through the city (120 frames).
  static CameraPath city_path() { return read_path(inputs_->file("fast.path")); }

  static inline test::SharedInputs* inputs_ = nullptr;
  static inline std::string world_file_;
  static inline World* world_ = nullptr;
  static inline GlContext* context_ = nullptr;
};

TEST_F(StratifiedSystem, StoredNearListsAreTheObjectsMeetingEachBox) {
  const StoredStratified stored(*world_);
  EXPECT_NEAR(stored.params().b, kBox, 1e-4);
  const Vec3 size = world_->info().bounds.size();
  EXPECT_NEAR(stored.params().v, eq22_viewcell_side(10 * M_PI / 180, kBox, std::max(size.x, size.z)), 0.01);
  ASSERT_GT(stored.partition().cell_count(), 20u);
  for (CellId c = 0; c < stored.partition().cell_count(); ++c) {
    const Aabb box = bounding_box(stored.partition().cell(c), kBox);
    std::vector<ObjectId> expected;
    for (ObjectId id = 0; id < world_->object_count(); ++id)
      if (world_->object(id).bounds.overlaps(box)) expected.push_back(id);
    EXPECT_EQ(stored.near(c), expected) << "cell " << c;
  }
}

// Whether the segment from `from` along unit `dir` for `length` metres meets `box` (slab test).
bool segment_meets(const Vec3& from, const Vec3& dir, float length, const Aabb& box) {
  float lo = 0.0f, hi = length;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dir[a]) < 1e-12f) {
      if (from[a] < box.min[a] || from[a] > box.max[a]) return false;
      continue;
    }
    float t0 = (box.min[a] - from[a]) / dir[a], t1 = (box.max[a] - from[a]) / dir[a];
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
  }
  return lo <= hi;
}

TEST_F(StratifiedSystem, FarFacesShowOnlyFarObjectsAtTheirTrueDistance) {
  const StoredStratified stored(*world_);
  size_t faces = 0;
  for (CellId c = 0; c < stored.partition().cell_count(); c += 7) {
    const std::vector<ObjectId> near = stored.near(c);
    const std::set<ObjectId> near_set(near.begin(), near.end());
    const CellFarField field = stored.far_field(c);
    EXPECT_LE(field.faces.size(), 6u);
    const Vec3 centre = stored.partition().cell(c).box.center();
    for (const FaceImage& f : field.faces) {
      ++faces;
      ASSERT_EQ(f.color.width, kResolution);
      for (size_t t = 0; t < f.ids.ids.size(); ++t) {
        const uint32_t id = f.ids.ids[t];
        if (id == kBackgroundId) {
          EXPECT_EQ(f.color.rgba[t * 4 + 3], 0) << "an empty texel is transparent";
          continue;
        }
        EXPECT_FALSE(near_set.count(id - 1)) << "near object " << id - 1 << " on a far face of cell " << c;
        // The texel's point lies outside the box, on the object it names (within its bounds).
        const int i = int(t % kResolution), j = int(t / kResolution);
        const Camera cam = face_camera(centre, kBox, f.face, 1e4f);
        const float x = (2.0f * i + 1) / kResolution - 1, y = (2.0f * j + 1) / kResolution - 1;
        const Vec3 dir = glm::normalize(cam.forward() + x * cam.right() + y * cam.up());
        // The stored depth is the farthest of its disparity step (docs/format.md): the true
        // point lies on the ray between the step's nearest and farthest distance.
        const float far = f.depth[t];
        EXPECT_GE(far, 0.5f * kBox * 0.999f);
        const double step = std::isinf(far) ? 0.0 : std::round(254.0 * 0.5 * kBox / far);
        const float near_end = float(0.5 * kBox * 254.0 / (step + 1.0));
        Aabb grown = world_->object(id - 1).bounds;
        grown.min -= Vec3(0.02f * near_end);
        grown.max += Vec3(0.02f * near_end);
        EXPECT_TRUE(segment_meets(centre + dir * near_end, dir, std::isinf(far) ? 1e30f : far - near_end, grown))
            << "texel " << t << " of cell " << c << " face " << f.face << " at " << near_end << "-" << far << " m";
      }
    }
  }
  EXPECT_GT(faces, 4u);
}

TEST_F(StratifiedSystem, MeasuredFarAngleIsZeroAtTheCentreAndWithinTheCheckersBound) {
  // From C the faces show every far point exactly where it is; from anywhere in the cell the
  // displacement stays under the numerical worst case for this cell size, box and model, which
  // is where Eq. 2.2's α is exceeded by a few per cent (digest §3.3).
  const StoredStratified stored(*world_);
  const Vec3 size = world_->info().bounds.size();
  const double bound = worst_case_angle(stored.params().v, kBox, {std::max(size.x, size.z), size.y}).angle;
  double largest = 0.0;
  for (CellId c = 0; c < stored.partition().cell_count(); c += 5) {
    const CellFarField field = stored.far_field(c);
    const ViewCell& cell = stored.partition().cell(c);
    Camera camera;
    camera.fov_y_deg = 100.0f;
    camera.aspect = 1.0f;
    camera.position = cell.box.center();
    for (const float yaw : {0.0f, 90.0f, 180.0f, 270.0f}) {
      camera.yaw_deg = yaw;
      camera.position = cell.box.center();
      EXPECT_LT(far_field_angle(field, cell.box.center(), kBox, camera), 1e-3) << "cell " << c;
      camera.position = cell.box.min + Vec3(0.0f, 0.25f, 0.0f);  // a corner, at eye height
      const double corner = far_field_angle(field, cell.box.center(), kBox, camera);
      largest = std::max(largest, corner);
      // The stored depth and the texel's centre add a little: half a texel of 90°/64.
      EXPECT_LE(corner, bound + 0.5 * (M_PI / 2) / kResolution) << "cell " << c << " yaw " << yaw;
    }
  }
  EXPECT_GT(largest, 0.2 * stored.params().alpha);  // the corners do see parallax
}

// Every 9th cell of the stored partition baked with `settings`; `triangles` gets what it drew.
std::vector<CellFarField> bake_cells(const World& world, const StoredStratified& stored, const BakeSettings& settings,
                                     uint64_t& triangles) {
  FarFieldBaker baker(world, settings);
  std::vector<CellFarField> fields;
  for (CellId c = 0; c < stored.partition().cell_count(); c += 9)
    fields.push_back(baker.bake(stored.partition().cell(c).box.center(), kBox, stored.near(c)));
  triangles = baker.triangles_drawn();
  return fields;
}

// The fraction of texels whose object differs between two bakes of the same cells.
double differing_ids(const std::vector<CellFarField>& a, const std::vector<CellFarField>& b) {
  uint64_t differing = 0, texels = 0;
  EXPECT_EQ(a.size(), b.size());
  for (size_t c = 0; c < std::min(a.size(), b.size()); ++c) {
    EXPECT_EQ(a[c].faces.size(), b[c].faces.size()) << "cell " << c;
    for (size_t f = 0; f < std::min(a[c].faces.size(), b[c].faces.size()); ++f)
      for (size_t t = 0; t < a[c].faces[f].ids.ids.size(); ++t) {
        differing += a[c].faces[f].ids.ids[t] != b[c].faces[f].ids.ids[t];
        ++texels;
      }
  }
  return texels ? double(differing) / double(texels) : 1.0;
}

TEST_F(StratifiedSystem, FarObjectsAtLevelsUnderHalfATexelShowTheSameFaces) {
  // Oracle: the thesis's bake, every far object at full detail. Levels whose error covers under
  // half a texel draw fewer triangles and nearly the same faces; levels far past it do not.
  const StoredStratified stored(*world_);
  uint64_t full_triangles = 0, fine_triangles = 0, coarse_triangles = 0;
  const auto full = bake_cells(*world_, stored, {.resolution = kResolution, .max_texels = 0.0f}, full_triangles);
  const auto fine = bake_cells(*world_, stored, {.resolution = kResolution, .max_texels = 0.5f}, fine_triangles);
  const auto coarse = bake_cells(*world_, stored, {.resolution = kResolution, .max_texels = 200.0f}, coarse_triangles);
  EXPECT_LT(fine_triangles, full_triangles);
  EXPECT_LT(coarse_triangles, fine_triangles);
  const double fine_differs = differing_ids(full, fine), coarse_differs = differing_ids(full, coarse);
  EXPECT_LT(fine_differs, 0.01);
  EXPECT_GT(coarse_differs, 2 * fine_differs);
  // The fixture's context draws again after the bakers' contexts are gone.
  Camera camera;
  apply(city_path().frames[0], camera);
  Renderer renderer(RenderSettings{});
  renderer.render(camera, std::vector<DrawItem>{}, [](const DrawItem&) -> const Mesh* { return nullptr; });
  EXPECT_GT(render_frame(*make_strategy("brute", *world_, StrategyOptions{}), renderer, camera).triangles, 0u);
}

TEST_F(StratifiedSystem, StoredDepthBoundsTheAngleFromAboveAndCloselyFromTheBakesExactDepth) {
  // Oracle: the baker's float depths. The 8-bit disparity a world stores measures the far-field
  // angle from any eye at least as large as they do, and larger by at most 2 % of α.
  const StoredStratified stored(*world_);
  uint64_t triangles = 0;
  const auto exact = bake_cells(*world_, stored, {.resolution = kResolution}, triangles);
  const double alpha = stored.params().alpha;
  double largest_excess = 0.0, largest = 0.0;
  size_t i = 0;
  for (CellId c = 0; c < stored.partition().cell_count(); c += 9, ++i) {
    StratifiedSizes sizes;
    const std::vector<uint8_t> record = encode_far_field(exact[i], kBox, sizes);
    const CellFarField stored_field = decode_far_field(record, kBox, kResolution, world_->object_count(), "test");
    const ViewCell& cell = stored.partition().cell(c);
    Camera camera;
    camera.fov_y_deg = 100.0f;
    camera.aspect = 1.0f;
    for (const Vec3 eye : {cell.box.min, cell.box.max, Vec3(cell.box.min.x, cell.box.max.y, cell.box.max.z)})
      for (const float yaw : {0.0f, 90.0f, 180.0f, 270.0f}) {
        camera.yaw_deg = yaw;
        camera.position = eye;
        const double truth = far_field_angle(exact[i], cell.box.center(), kBox, camera);
        const double measured = far_field_angle(stored_field, cell.box.center(), kBox, camera);
        EXPECT_GE(measured, truth - 1e-6) << "cell " << c << " yaw " << yaw;
        largest_excess = std::max(largest_excess, measured - truth);
        largest = std::max(largest, truth);
      }
  }
  EXPECT_GT(largest, 0.2 * alpha);
  EXPECT_LE(largest_excess, 0.02 * alpha);
}

TEST_F(StratifiedSystem, APoolOfBakersGivesTheRecordsOfOneBakerInOrder) {
  // Oracle: one baker on this thread, each cell encoded as it is baked.
  const StoredStratified stored(*world_);
  const BakeSettings settings{.resolution = kResolution};
  std::vector<std::vector<ObjectId>> near_lists;  // the jobs' spans point into these
  for (CellId c = 0; c < stored.partition().cell_count(); c += 11) near_lists.push_back(stored.near(c));
  std::vector<BakeJob> jobs;
  std::vector<std::vector<uint8_t>> expected;
  {
    FarFieldBaker baker(*world_, settings);
    for (size_t i = 0; i < near_lists.size(); ++i) {
      const std::span<const ObjectId> near = near_lists[i];
      jobs.push_back({stored.partition().cell(CellId(11 * i)).box.center(), kBox, near});
      StratifiedSizes unused;
      expected.push_back(encode_far_field(baker.bake(jobs.back().centre, kBox, near), kBox, unused));
    }
  }
  ASSERT_GT(jobs.size(), 4u);
  for (const int threads : {1, 3}) {
    BakePool pool(*world_, settings, threads, jobs);
    for (size_t i = 0; i < jobs.size(); ++i) EXPECT_EQ(pool.next(), expected[i]) << threads << " threads, job " << i;
    EXPECT_GT(pool.triangles_drawn(), 0u);
    EXPECT_THROW(pool.next(), Error);  // no job left
  }
  // A worker's error reaches the caller; a pool left with jobs undone stops when destroyed.
  BakePool bad(*world_, {.resolution = 0}, 2, jobs);
  EXPECT_THROW(bad.next(), Error);
  BakePool abandoned(*world_, settings, 2, jobs);
  EXPECT_FALSE(abandoned.next().empty());
  EXPECT_THROW(BakePool(*world_, settings, 0, jobs), Error);
}

TEST_F(StratifiedSystem, ShardsMergeAndAKilledBakeResumesIntoTheWorldOfOneRun) {
  // Oracle: one process baking every cell along the path.
  const test::TempDir dir;
  const std::string options = " --alpha 10 --box 120 --resolution 32 --along-margin 40 --along " + inputs_->file("fast.path") + " --json";
  const auto build = [&](const std::string& args) {
    const test::CommandResult r = test::run_cellwalk("stratify build " + world_file_ + " " + args + options);
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.output;
    return r.exit_code == 0 ? nlohmann::json::parse(r.output) : nlohmann::json::object();
  };
  const nlohmann::json one = build("-o " + dir.file("one.cww"));
  ASSERT_GT(one["baked_now"].get<int>(), 3);
  const std::vector<uint8_t> expected = test::slurp(dir.file("one.cww"));
  int baked = 0;
  for (int i = 0; i < 3; ++i) baked += build("--shard " + std::to_string(i) + "/3 -o " + dir.file("p" + std::to_string(i)))["baked_now"].get<int>();
  EXPECT_EQ(baked, one["baked_now"].get<int>());
  build("-o " + dir.file("merged.cww") + " --merge " + dir.file("p2") + " " + dir.file("p0") + " " + dir.file("p1"));
  EXPECT_EQ(test::slurp(dir.file("merged.cww")), expected);

  // A run killed in the middle of a record: the torn record is baked again, the rest resumed.
  const std::string checkpoint = dir.file("two.cww.stratify-checkpoint");
  build("--shard 0/1 -o " + checkpoint);
  std::filesystem::resize_file(checkpoint, std::filesystem::file_size(checkpoint) - 100);
  const nlohmann::json resumed = build("-o " + dir.file("two.cww"));
  EXPECT_EQ(resumed["baked_now"], 1);
  EXPECT_EQ(resumed["resumed"].get<int>(), one["baked_now"].get<int>() - 1);
  EXPECT_EQ(test::slurp(dir.file("two.cww")), expected);
  EXPECT_FALSE(std::filesystem::exists(checkpoint));

  // Parts that are not one whole run, and a checkpoint of another run, are refused in one line
  // and nothing is written.
  test::spit(dir.file("junk"), {'j', 'u', 'n', 'k', 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});
  const test::CommandResult other = test::run_cellwalk("stratify build " + world_file_ + " --shard 0/1 -o " + dir.file("other") +
                                                       " --alpha 8 --box 120 --resolution 32");
  ASSERT_EQ(other.exit_code, 0) << other.output;
  std::filesystem::copy_file(dir.file("other"), dir.file("three.cww.stratify-checkpoint"));
  for (const std::string& args : {"-o " + dir.file("bad.cww") + " --merge " + dir.file("p0") + " " + dir.file("p1"),
                                  "-o " + dir.file("bad.cww") + " --merge " + dir.file("p0") + " " + dir.file("p0") + " " + dir.file("p1"),
                                  "-o " + dir.file("bad.cww") + " --merge " + dir.file("junk"),
                                  "-o " + dir.file("bad.cww") + " --merge " + dir.file("other"),
                                  "-o " + dir.file("three.cww"), std::string("--shard 3/3"), "--shard 0/1 --merge " + dir.file("p0")}) {
    const test::CommandResult r = test::run_cellwalk("stratify build " + world_file_ + " " + args + options);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.cww")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("three.cww")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("three.cww.stratify-checkpoint")));  // another run's work is kept
}

TEST_F(StratifiedSystem, FaceQuadMatchesItsCamera) {
  const Vec3 c(10.0f, 1.7f, -20.0f);
  for (int face = 0; face < kFaceCount; ++face) {
    const FarFace quad = face_quad(c, kBox, face, 0);
    const Camera cam = face_camera(c, kBox, face, 1e4f);
    for (const auto& [s, t] : {std::pair{0.25f, 0.75f}, {0.5f, 0.5f}, {0.9f, 0.1f}}) {
      const Vec4 clip = cam.view_projection() * Vec4(quad.origin + s * quad.u + t * quad.v, 1.0f);
      EXPECT_NEAR(clip.x / clip.w, 2 * s - 1, 1e-4) << face;
      EXPECT_NEAR(clip.y / clip.w, 2 * t - 1, 1e-4) << face;
    }
    EXPECT_NEAR(glm::length(quad.u), kBox, 1e-3);
  }
}

TEST_F(StratifiedSystem, DamagedFarRecordsAreRefusedWithWhere) {
  const StoredStratified stored(*world_);
  CellId c = 0;
  while (stored.far_field_bytes(c) < 64) ++c;
  StratifiedSizes sizes;
  const std::vector<uint8_t> good = encode_far_field(stored.far_field(c), kBox, sizes);
  EXPECT_NO_THROW(decode_far_field(good, kBox, kResolution, world_->object_count(), "x"));
  std::vector<uint8_t> truncated(good.begin(), good.end() - 5);
  EXPECT_THROW(decode_far_field(truncated, kBox, kResolution, world_->object_count(), "x"), Error);
  std::vector<uint8_t> mask = good;
  mask[0] |= 0x80;
  EXPECT_THROW(decode_far_field(mask, kBox, kResolution, world_->object_count(), "x"), Error);
  EXPECT_THROW(decode_far_field(good, kBox, kResolution * 2, world_->object_count(), "x"), Error);
  EXPECT_THROW(decode_far_field(good, kBox, kResolution, 1, "x"), Error);  // ids past the objects
}

std::vector<FrameStats> frames_of(const std::string& strategy, const World& world, const CameraPath& path,
                                  Renderer& renderer, std::vector<Image>* images, uint64_t budget = 0) {
  StrategyOptions options;
  options.memory_budget_bytes = budget;
  const std::unique_ptr<Strategy> s = make_strategy(strategy, world, options);
  Camera camera;
  camera.aspect = 1.0f;
  camera.fov_y_deg = 90.0f;
  std::vector<FrameStats> out;
  for (const PathFrame& f : path.frames) {
    apply(f, camera);
    out.push_back(render_frame(*s, renderer, camera, f.time));
    if (images) images->push_back(renderer.read_color());
  }
  return out;
}

TEST_F(StratifiedSystem, ShowBruteDrawsWhatBruteDrawsAndFullDrawsFewerTriangles) {
  RenderSettings settings;
  settings.width = settings.height = 128;
  Renderer renderer(settings);
  const CameraPath path = city_path();
  std::vector<Image> brute_images, show_brute_images;
  const auto brute = frames_of("brute", *world_, path, renderer, &brute_images);
  const auto show_brute = frames_of("stratified:show=brute", *world_, path, renderer, &show_brute_images);
  const auto full = frames_of("stratified", *world_, path, renderer, nullptr);
  const auto near = frames_of("stratified:show=near", *world_, path, renderer, nullptr);
  uint64_t brute_tris = 0, full_tris = 0;
  for (size_t i = 0; i < path.frames.size(); ++i) {
    EXPECT_EQ(show_brute_images[i].rgba, brute_images[i].rgba) << "frame " << i;
    brute_tris += brute[i].triangles;
    full_tris += full[i].triangles;
    EXPECT_LE(near[i].triangles + 12, full[i].triangles + 12);
  }
  EXPECT_LT(full_tris, brute_tris);
}

TEST_F(StratifiedSystem, BudgetHoldsTheFacesOrTheRunIsRefused) {
  RenderSettings settings;
  settings.width = settings.height = 64;
  Renderer renderer(settings);
  const CameraPath path = city_path();
  const uint64_t budget = 8ull << 20;
  StrategyOptions options;
  options.memory_budget_bytes = budget;
  Camera camera;
  for (const char* name : {"stratified", "stratified:fade=4"}) {  // a fading cell is charged too
    const std::unique_ptr<Strategy> s = make_strategy(name, *world_, options);
    for (const PathFrame& f : path.frames) {
      apply(f, camera);
      render_frame(*s, renderer, camera, f.time);
      EXPECT_LE(s->resident_bytes(), budget) << name;
    }
    EXPECT_LE(s->peak_resident_bytes(), budget) << name;
    EXPECT_GT(s->peak_resident_bytes(), uint64_t(kResolution) * kResolution * 12) << name;  // a face was held
  }
  options.memory_budget_bytes = 64 << 10;
  EXPECT_THROW(
      {
        const std::unique_ptr<Strategy> tiny = make_strategy("stratified", *world_, options);
        apply(path.frames.front(), camera);
        render_frame(*tiny, renderer, camera, 0.0);
      },
      Error);
}

TEST_F(StratifiedSystem, PrefetchHasTheNextCellReadyAtTheCrossing) {
  RenderSettings settings;
  settings.width = settings.height = 64;
  Renderer renderer(settings);
  const CameraPath path = city_path();
  StratifiedCounters counted[2];
  std::vector<Image> images[2];
  for (const int prefetch : {0, 1}) {
    const std::unique_ptr<Strategy> s =
        make_strategy(prefetch ? "stratified" : "stratified:prefetch=0", *world_, StrategyOptions{});
    Camera camera;
    uint64_t stall_frames = 0;
    for (const PathFrame& f : path.frames) {
      apply(f, camera);
      stall_frames += render_frame(*s, renderer, camera, f.time).stall;
      images[prefetch].push_back(renderer.read_color());
    }
    counted[prefetch] = dynamic_cast<StratifiedStrategy&>(*s).counters();
    EXPECT_EQ(stall_frames, counted[prefetch].stalls);
  }
  ASSERT_GT(counted[0].crossings, 1u) << "the path must cross cells";
  EXPECT_EQ(counted[0].stalls, counted[0].crossings);  // the thesis: every crossing loads in its frame
  EXPECT_EQ(counted[1].crossings, counted[0].crossings);
  EXPECT_LT(counted[1].stalls, counted[0].stalls);
  EXPECT_GT(counted[1].prefetch_hits, 0u);
  for (size_t i = 0; i < images[0].size(); ++i) EXPECT_EQ(images[0][i].rgba, images[1][i].rgba) << "frame " << i;
}

// The faces of `faces` whose opacity is below 1 (`fading`) or not, all at opacity `opacity`.
std::vector<FarFace> faces_where(std::span<const FarFace> faces, bool fading, float opacity) {
  std::vector<FarFace> out;
  for (FarFace f : faces)
    if ((f.opacity < 1.0f) == fading) {
      f.opacity = opacity;
      out.push_back(f);
    }
  return out;
}

TEST_F(StratifiedSystem, CrossFadeBlendsTheCellLeftOverTheNewOneForItsFramesAndKeepsTheNewIds) {
  RenderSettings settings;
  settings.width = settings.height = 64;
  Renderer renderer(settings);
  const CameraPath path = city_path();
  constexpr int kFade = 3;
  const std::unique_ptr<Strategy> hard = make_strategy("stratified", *world_, StrategyOptions{});
  const std::unique_ptr<Strategy> soft = make_strategy("stratified:fade=3", *world_, StrategyOptions{});
  EXPECT_EQ(soft->name(), "stratified:fade=3");
  const StoredStratified stored(*world_);
  Camera camera;
  int since_crossing = -1;  // frames since the last crossing after the first frame; -1 before any
  size_t blended_pixels = 0;
  std::optional<CellId> cell, left;  // the camera's cell, and the one it left at the last crossing
  for (size_t i = 0; i < path.frames.size(); ++i) {
    apply(path.frames[i], camera);
    render_frame(*hard, renderer, camera, path.frames[i].time);
    const Image hard_color = renderer.read_color();
    const IdImage hard_ids = renderer.read_ids();
    render_frame(*soft, renderer, camera, path.frames[i].time);
    const Image soft_color = renderer.read_color();
    if (dynamic_cast<StratifiedStrategy&>(*soft).crossed() && i > 0) {
      since_crossing = 0;
      left = cell;
    } else if (since_crossing >= 0) {
      ++since_crossing;
    }
    cell = stored.partition().locate(camera.position);
    // The fading faces keep the ids underneath; the objects near only in the cell left stay
    // polygons while it fades (its faces do not show them) and may cover other ids.
    std::set<uint32_t> kept;
    if (since_crossing >= 0 && since_crossing < kFade && left)
      for (const ObjectId id : stored.near(*left)) kept.insert(id + 1);
    const IdImage soft_ids = renderer.read_ids();
    for (size_t p = 0; p < soft_ids.ids.size(); ++p)
      if (soft_ids.ids[p] != hard_ids.ids[p]) {
        EXPECT_TRUE(kept.count(soft_ids.ids[p])) << "frame " << i << " pixel " << p;
      }
    const std::span<const FarFace> faces = soft->far_faces();
    const bool fading = since_crossing >= 0 && since_crossing < kFade;
    const std::vector<FarFace> old_faces = faces_where(faces, true, 1.0f);
    EXPECT_EQ(!old_faces.empty(), fading) << "frame " << i;
    for (const FarFace& f : faces)
      if (f.opacity < 1.0f) {
        EXPECT_FLOAT_EQ(f.opacity, 1.0f - float(since_crossing + 1) / (kFade + 1)) << "frame " << i;
      }
    if (!fading) {
      EXPECT_EQ(soft_color.rgba, hard_color.rgba) << "frame " << i;
      continue;
    }
    ASSERT_TRUE(left.has_value());
    // Oracle: the new faces alone (A), the old faces alone and opaque (B); with both, a pixel the
    // old faces cover is opacity·B + (1 − opacity)·A, any other is A.
    const float a = faces.back().opacity;  // the old faces come last
    auto draw = [&](const std::vector<FarFace>& drawn) {
      renderer.render(camera, std::vector<DrawItem>{}, [](const DrawItem&) -> const Mesh* { return nullptr; }, drawn);
    };
    draw(faces_where(faces, false, 1.0f));
    const Image only_new = renderer.read_color();
    draw(old_faces);
    const Image only_old = renderer.read_color();
    const IdImage old_ids = renderer.read_ids();
    draw({faces.begin(), faces.end()});
    const Image both = renderer.read_color();
    // Pixels at the edge of what the old faces cover are skipped: there the filtered colour's
    // alpha, not the texel's id, decides whether a texel is drawn.
    const int w = old_ids.width, h = old_ids.height;
    auto covered = [&](int x, int y) { return old_ids.ids[size_t(std::clamp(y, 0, h - 1)) * w + std::clamp(x, 0, w - 1)] != kBackgroundId; };
    for (size_t p = 0; p < old_ids.ids.size(); ++p)
      for (int ch = 0; ch < 3; ++ch) {
        const int x = int(p % w), y = int(p / w);
        const bool in = covered(x, y);
        if (covered(x - 1, y) != in || covered(x + 1, y) != in || covered(x, y - 1) != in || covered(x, y + 1) != in) continue;
        const float n = only_new.rgba[p * 4 + ch], o = only_old.rgba[p * 4 + ch];
        const float expected = in ? a * o + (1.0f - a) * n : n;
        ASSERT_NEAR(both.rgba[p * 4 + ch], expected, 2.0f) << "frame " << i << " pixel " << p;
        blended_pixels += old_ids.ids[p] != kBackgroundId && ch == 0 && std::abs(o - n) > 8.0f;
      }
  }
  EXPECT_GT(dynamic_cast<StratifiedStrategy&>(*soft).counters().faded_frames, 0u);
  EXPECT_GT(blended_pixels, 0u) << "the fade must show somewhere";
}

TEST_F(StratifiedSystem, TurningBackIntoTheFadingCellLoadsNothing) {
  // Frames at the centres of cells A, B, A: with the thesis's run time (no prefetch) each
  // crossing loads its cell, a stall; with a fade, A is still held when the viewer turns back.
  const StoredStratified stored(*world_);
  CellId a = 0, b = 0;
  for (CellId c = 1; c < stored.partition().cell_count() && b == 0; ++c)
    if (stored.partition().cell(c).computed() && !stored.far_field(c).faces.empty() && !stored.far_field(0).faces.empty()) b = c;
  ASSERT_NE(b, 0u);
  RenderSettings settings;
  settings.width = settings.height = 32;
  Renderer renderer(settings);
  for (const int fade : {0, 4}) {
    const std::unique_ptr<Strategy> s =
        make_strategy("stratified:prefetch=0" + std::string(fade ? ",fade=4" : ""), *world_, StrategyOptions{});
    Camera camera;
    uint64_t resident_in_a = 0;
    int frame = 0;
    for (const CellId c : {a, b, a}) {
      camera.position = stored.partition().cell(c).box.center();
      render_frame(*s, renderer, camera, 0.1 * frame++);
      if (c == a) resident_in_a = resident_in_a ? resident_in_a : s->resident_bytes();
    }
    const StratifiedCounters& counted = dynamic_cast<StratifiedStrategy&>(*s).counters();
    EXPECT_EQ(counted.crossings, 2u) << "fade " << fade;
    EXPECT_EQ(counted.stalls, fade ? 1u : 2u) << "fade " << fade;
    // Back in A, B fades in its place: A is held once, not twice.
    if (fade) {
      EXPECT_LE(s->resident_bytes(), resident_in_a + stored.load_bound(b));
    }
  }
}

TEST_F(StratifiedSystem, ABudgetTooSmallForACellIsAnErrorNotACrash) {
  // Budgets between what the constructor checks and one cell's far field: the crossing that
  // cannot be held must throw Error and leave the budget balanced (no abort in a destructor).
  RenderSettings settings;
  settings.width = settings.height = 32;
  Renderer renderer(settings);
  const CameraPath path = city_path();
  int refused = 0, ran = 0;
  for (uint64_t budget = 128 << 10; budget <= (3u << 20); budget += 64 << 10) {
    std::map<std::string, bool> done;
    for (const char* name : {"stratified", "stratified:prefetch=0", "stratified:prefetch=0,fade=8"}) {
      StrategyOptions options;
      options.memory_budget_bytes = budget;
      try {
        const std::unique_ptr<Strategy> s = make_strategy(name, *world_, options);
        Camera camera;
        for (size_t i = 0; i < path.frames.size(); i += 10) {
          apply(path.frames[i], camera);
          render_frame(*s, renderer, camera, path.frames[i].time);
          EXPECT_LE(s->peak_resident_bytes(), budget);
        }
        ++ran;
        done[name] = true;
      } catch (const Error&) {
        ++refused;
      }
    }
    // A fading cell gives its bytes to a crossing that needs them: a fade never makes a run fail.
    EXPECT_EQ(done["stratified:prefetch=0,fade=8"], done["stratified:prefetch=0"]) << budget << " bytes";
  }
  EXPECT_GT(refused, 0);
  EXPECT_GT(ran, 0);
}

TEST(StratifiedCodec, DepthDecodesToTheFarthestOfItsStep) {
  // One 3 × 3 face: nothing; the face itself (b/2); just past it; 3b; a step boundary; past
  // 254·b/2 (the last step, decoded as infinitely far); nothing in the last row.
  const float b = 100.0f;
  FaceImage face;
  face.color = {3, 3, std::vector<uint8_t>(3 * 3 * 4, 255)};
  face.ids = {3, 3, std::vector<uint32_t>(9, 1)};
  face.depth = {0.0f, 0.5f * b, 0.5f * b * 1.001f, 3.0f * b, float(0.5 * b * 254.0 / 100.0), 0.5f * b * 300.0f, 0, 0, 0};
  CellFarField field;
  field.faces.push_back(face);
  StratifiedSizes sizes;
  const CellFarField back = decode_far_field(encode_far_field(field, b, sizes), b, 3, 1, "test");
  const std::vector<float>& d = back.faces.at(0).depth;
  EXPECT_EQ(d[0], 0.0f);                                // nothing stays nothing
  EXPECT_FLOAT_EQ(d[1], 0.5f * b);                      // the face: the nearest step's far end is b/2
  for (size_t i = 2; i < 5; ++i) {
    EXPECT_GE(d[i], face.depth[i]) << i;                // never nearer than the truth
    const double step = 0.5 * b / face.depth[i] - 0.5 * b / d[i];  // in disparity
    EXPECT_LE(step, 1.0 / 254 + 1e-9) << i;             // within one step
  }
  EXPECT_TRUE(std::isinf(d[5]));
  EXPECT_EQ(sizes.faces, 1u);
}

TEST(StratifiedName, SettingsAreParsedAndBadOnesRefused) {
  EXPECT_EQ(parse_stratified_strategy_name("stratified:show=far-texture").show, StratifiedConfig::Show::kFarTexture);
  EXPECT_FALSE(parse_stratified_strategy_name("stratified:cull=0").cull);
  EXPECT_FALSE(parse_stratified_strategy_name("stratified:prefetch=0,lookahead=3").prefetch);
  EXPECT_DOUBLE_EQ(parse_stratified_strategy_name("stratified:lookahead=3").lookahead_s, 3.0);
  EXPECT_THROW(parse_stratified_strategy_name("stratified:show=nothing"), Error);
  EXPECT_THROW(parse_stratified_strategy_name("stratified:speed=2"), Error);
  EXPECT_EQ(parse_stratified_strategy_name("stratified:fade=4").fade_frames, 4);
  EXPECT_THROW(parse_stratified_strategy_name("stratified:fade=1.5"), Error);
  EXPECT_THROW(parse_stratified_strategy_name("stratified:fade=61"), Error);
}

TEST(StratifiedWorld, AWorldWithoutThePreprocessingNamesTheCommand) {
  const test::TempDir dir;
  const World world(test::write_street_world(dir, 4));
  try {
    StoredStratified stored(world);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("stratify build"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cellwalk

// ---- cellwalk bench stratified -----------------------------------------------------------------

#include "experiments/stratified/stratified_report.hpp"

namespace cellwalk {
namespace {

// The whole bench at a tiny scale: the report and its files are written, and what must hold
// whatever the machine holds: brute is its own baseline, stratified draws fewer triangles, its
// far angle is positive and within the checker's worst case, and the smaller α has the smaller
// cells and the smaller angle.
TEST(StratifiedBench, BadScaleOptionsAreRefusedBeforeAnythingIsBuilt) {
  const test::TempDir dir;
  for (const char* options : {"--scale-blocks 2 --scale-strategy brute", "--scale-blocks 2 --scale-strategy lod --scale-strategy lod",
                                     "--scale-blocks 2 --scale-strategy stratified", "--scale-blocks 2 --scale-strategy nosuch",
                                     "--scale-strategy lod", "--scale-frames 40"}) {
    const test::CommandResult r = test::run_cellwalk("bench stratified --out " + dir.file("out") + " --work-dir " + dir.file("work") + " " + std::string(options));
    EXPECT_NE(r.exit_code, 0) << options;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << options << ": " << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("work")));
}

TEST(StratifiedBench, WritesReportWithSaneFigures) {
  const test::TempDir dir;
  StratifiedBenchParams p;
  p.city.blocks_x = p.city.blocks_z = 3;
  p.alphas_deg = {10.0, 2.0};
  p.box = 120.0;
  p.resolution = 32;
  p.frames = 30;
  p.width = p.height = 64;
  p.fidelity_every = 10;
  p.images = 1;
  p.out_dir = dir.file("results");
  p.work_dir = dir.file("work");
  p.command_line = "cellwalk bench stratified --blocks-x 3";
  p.path_seeds = {3};
  p.scale_blocks = 4;
  p.scale_frames = 30;
  p.scale_others_every = 4;
  p.scale_fidelity_every = 10;
  p.scale_strategies = {"lod"};
  p.bake_all_up_to = 1000;  // α = 10° baked whole, 2° along the path
  p.fade_frames = 3;
  const nlohmann::ordered_json s = run_stratified_bench(p);
  const std::filesystem::path out = p.out_dir;
  const std::vector<uint8_t> bytes = test::slurp((out / "stratified.md").string());
  const std::string md(bytes.begin(), bytes.end());
  for (const char* heading : {"## Table 6.1", "## Frame time", "## Fidelity", "## Crossings", "## At city scale"})
    EXPECT_NE(md.find(heading), std::string::npos) << heading;
  // Table 6.1: a configuration under the limit is baked whole (measured), a larger one along the path.
  const auto& t61 = s["table61"];
  ASSERT_EQ(t61.size(), 2u);
  EXPECT_LE(t61[0]["cells"].get<uint64_t>(), p.bake_all_up_to);
  EXPECT_EQ(t61[0]["baked"], t61[0]["cells"]);
  EXPECT_GT(t61[1]["cells"].get<uint64_t>(), p.bake_all_up_to);
  EXPECT_LT(t61[1]["baked"].get<uint64_t>(), t61[1]["cells"].get<uint64_t>());
  EXPECT_NE(md.find("(measured)"), std::string::npos);
  EXPECT_NE(md.find("(from the rate)"), std::string::npos);
  for (const auto& c : t61) EXPECT_GT(c["stored_bytes"].get<uint64_t>(), c["color_bytes"].get<uint64_t>());
  EXPECT_NE(md.find(p.command_line), std::string::npos);
  for (const char* file : {"table61.csv", "frames.csv", "frame-times-seed3.svg"})
    EXPECT_GT(std::filesystem::file_size(out / "stratified" / file), 0u) << file;
  const auto& walks = s["paths"]["3"];
  EXPECT_DOUBLE_EQ(walks["brute"]["speedup"].get<double>(), 1.0);
  EXPECT_LT(walks["stratified-10.0"]["triangles"].get<uint64_t>(), walks["brute"]["triangles"].get<uint64_t>() + 8);
  EXPECT_EQ(walks["stratified-10.0-noprefetch"]["stall_frames"], walks["stratified-10.0-noprefetch"]["crossings"]);
  // The cross-fading walker crosses where the hard one does; both track how much a frame changes.
  EXPECT_EQ(walks["stratified-10.0-fade=3"]["crossings"], walks["stratified-10.0"]["crossings"]);
  for (const char* w : {"stratified-10.0", "stratified-10.0-fade=3"}) EXPECT_GT(walks[w]["change_elsewhere"].get<double>(), 0.0) << w;
  const double coarse = walks["stratified-10.0"]["max_far_angle_deg"].get<double>();
  const double fine = walks["stratified-2.0"]["max_far_angle_deg"].get<double>();
  EXPECT_GT(coarse, 0.0);
  EXPECT_LT(fine, coarse);
  EXPECT_LT(coarse, 10.0 * 1.1 + 90.0 / 32);  // the checker's few per cent and half a texel
  EXPECT_LT(fine, 2.0 * 1.1 + 90.0 / 32);
  // The per-frame CSV shows each crossing and whether it stalled: the thesis's run time stalls
  // at every crossing.
  std::ifstream csv(out / "stratified" / "frames.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "path,strategy,frame,frame_ms,triangles,crossing,stall,load_ms,far_angle_deg");
  int noprefetch_crossings = 0;
  while (std::getline(csv, line)) {
    std::vector<std::string> field;
    std::stringstream row(line);
    for (std::string f; std::getline(row, f, ',');) field.push_back(f);
    ASSERT_EQ(field.size(), 9u) << line;
    if (field[1] != "stratified-10.0-noprefetch" || field[2] == "0" || field[5] != "1") continue;
    ++noprefetch_crossings;
    EXPECT_EQ(field[6], "1") << line;
  }
  EXPECT_EQ(noprefetch_crossings, walks["stratified-10.0-noprefetch"]["crossings"].get<int>());
  // At city scale: a larger world; stratified draws every frame, the others every 4th and the
  // compared ones (frames 0, 4, 8, 10, 12, 16, 20, 24, 28: 9 of 30).
  const auto& scale = s["scale"];
  EXPECT_GT(scale["triangles"].get<uint64_t>(), s["world"]["triangles"].get<uint64_t>());
  EXPECT_EQ(scale["walks"]["stratified-10.0"]["frames"], 30);
  EXPECT_EQ(scale["walks"]["brute"]["frames"], 9);
  EXPECT_EQ(scale["walks"]["lod"]["frames"], 9);
  EXPECT_EQ(scale["walks"]["stratified-10.0-alone"]["frames"], 30);  // its stalls counted on a walk of its own
  // Speed-ups are over the frames brute drew: stratified's mean there is another figure.
  EXPECT_GT(scale["walks"]["stratified-10.0"]["frame_ms_on_brute_frames"].get<double>(), 0.0);
  EXPECT_NEAR(scale["walks"]["stratified-10.0"]["speedup"].get<double>(),
              scale["walks"]["brute"]["frame_ms"].get<double>() /
                  scale["walks"]["stratified-10.0"]["frame_ms_on_brute_frames"].get<double>(), 1e-9);
  EXPECT_LT(scale["walks"]["stratified-10.0"]["triangles"].get<uint64_t>(), scale["walks"]["brute"]["triangles"].get<uint64_t>());
  EXPECT_GT(scale["walks"]["lod"]["visible"].get<uint64_t>(), 0u);
}

}  // namespace
}  // namespace cellwalk
