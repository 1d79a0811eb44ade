// Li & Chiang (seed 003): the relevance matrix against the two the slides print, the
// configurations' direction test against sampled oracles, and the strategy end to end: every
// visible object drawn, the budget held, the seed's four cases run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <numeric>
#include <set>

#include <nlohmann/json.hpp>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/lichiang/configurations.hpp"
#include "cellwalk/systems/lichiang/lichiang_strategy.hpp"
#include "cellwalk/systems/lichiang/relevance.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "experiments/lichiang/lichiang_report.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using namespace lichiang;
constexpr double kPi = std::numbers::pi;

// "Examples of Computed Relevance Matrices", as printed.
TEST(LiChiangRelevance, ReproducesBothPrintedMatricesCellForCell) {
  const std::vector<std::vector<int>> still = {{209, 235, 251, 235, 209},
                                               {216, 243, 254, 243, 216},
                                               {213, 244, 255, 244, 213},
                                               {188, 224, 235, 224, 188},
                                               {133, 169, 175, 169, 133}};
  const std::vector<std::vector<int>> turning = {{157, 209, 246, 225, 195},
                                                 {177, 224, 251, 235, 209},
                                                 {188, 235, 254, 243, 216},
                                                 {181, 236, 255, 244, 213},
                                                 {136, 205, 235, 224, 188}};
  EXPECT_EQ(relevance_matrix(0.0, 0.0), still);
  EXPECT_EQ(relevance_matrix(0.5, -0.5), turning);
}

// a(φ) is a_min ahead, rises to its peak at f_max and falls back to a_min, continuously; ω < 0
// (turning right) puts the peak behind on the left, and keeps the right side more relevant.
TEST(LiChiangRelevance, FalloffIsContinuousAndTurnsWithTheViewer) {
  const RelevanceParams p;
  for (const double omega : {-2.0, -0.5, 0.0, 0.3, 1.5}) {
    SCOPED_TRACE(omega);
    const double f_max = relevance_peak_angle(omega);
    ASSERT_GT(f_max, 0.0);
    ASSERT_LT(f_max, 2.0 * kPi);
    EXPECT_DOUBLE_EQ(relevance_falloff(0.0, omega), p.a_min);
    EXPECT_NEAR(relevance_falloff(2.0 * kPi - 1e-12, omega), p.a_min, 1e-9);
    EXPECT_NEAR(relevance_falloff(f_max - 1e-9, omega), relevance_falloff(f_max + 1e-9, omega), 1e-6);
    for (double phi = 0.01; phi < 2.0 * kPi; phi += 0.01)
      EXPECT_LE(relevance_falloff(phi, omega), relevance_falloff(f_max, omega) + 1e-9);
  }
  EXPECT_DOUBLE_EQ(relevance_falloff(kPi, 0.0), p.a_max);
  EXPECT_DOUBLE_EQ(relevance(1, 1, 0.0), relevance(1, -1, 0.0));  // still: left and right alike
  EXPECT_GT(relevance(0, 1, -0.5), relevance(0, -1, -0.5));       // turning right: right ahead of left
  EXPECT_GT(relevance(0, -1, 0.5), relevance(0, 1, 0.5));
  EXPECT_GT(relevance(1, 0, 0.0), relevance(-1, 0, 0.0));         // ahead before behind
}

// The window holds (2r + 1)² grid offsets around the cell ⌈ν⌉ steps along the heading, most
// relevant first; turned with the viewer, the same offsets in its frame get the same w.
TEST(LiChiangRelevance, WindowIsShiftedAheadTurnedWithTheViewerAndOrdered) {
  for (const double nu : {0.0, 0.5, 1.7}) {
    for (int octant = 0; octant < 8; ++octant) {
      const double yaw = octant * kPi / 4.0;
      const std::vector<RelevanceEntry> window = relevance_window(nu, -0.3, yaw);
      ASSERT_EQ(window.size(), 25u);
      EXPECT_EQ(window.front().dx, 0);
      EXPECT_EQ(window.front().dz, 0);
      EXPECT_DOUBLE_EQ(window.front().w, 255.0);
      const int shift = nu > 0 ? int(std::ceil(nu)) : 0;
      const int sx = int(std::lround(-std::sin(yaw))) * shift, sz = int(std::lround(-std::cos(yaw))) * shift;
      std::set<std::pair<int, int>> offsets;
      for (size_t i = 0; i < window.size(); ++i) {
        const RelevanceEntry& e = window[i];
        if (i > 0) {
          EXPECT_GE(window[i - 1].w, e.w);
        }
        EXPECT_LE(std::abs(e.dx - sx), 2);
        EXPECT_LE(std::abs(e.dz - sz), 2);
        offsets.insert({e.dx, e.dz});
        const double ahead = -e.dx * std::sin(yaw) - e.dz * std::cos(yaw);
        const double right = e.dx * std::cos(yaw) - e.dz * std::sin(yaw);
        EXPECT_NEAR(e.w, relevance(ahead, right, -0.3), 1e-9);
      }
      EXPECT_EQ(offsets.size(), 25u);
    }
  }
}

Aabb random_box(Random& rng, float extent) {
  auto u = [&](double lo, double hi) { return float(rng.uniform(lo, hi)); };
  const Vec3 a(u(-extent, extent), u(0.0, 5.0), u(-extent, extent));
  return {a, a + Vec3(u(0.1, 8.0), u(0.1, 8.0), u(0.1, 8.0))};
}

Vec3 random_point(Random& rng, const Aabb& b) {
  return {float(rng.uniform(b.min.x, b.max.x)), float(rng.uniform(b.min.y, b.max.y)), float(rng.uniform(b.min.z, b.max.z))};
}

double gap(double a, double b) { return std::abs(std::remainder(a - b, 2.0 * kPi)); }

// Oracle: directions between sampled point pairs. Each lies in the range (it is conservative),
// and both ends of the range are approached by some pair (it is tight).
TEST(LiChiangConfigurations, DirectionsBetweenBoxesAgainstSampledPairs) {
  Random rng(7);
  int disjoint = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Aabb from = random_box(rng, 20.0f), to = random_box(rng, 20.0f);
    const YawRange range = directions_between(from, to);
    const bool overlap = from.max.x >= to.min.x && to.max.x >= from.min.x && from.max.z >= to.min.z && to.max.z >= from.min.z;
    ASSERT_EQ(range.all, overlap) << trial;
    if (range.all) continue;
    ++disjoint;
    double near_lo = 10.0, near_hi = 10.0;
    for (int s = 0; s < 4000; ++s) {
      // corners as well as inner points: the extremes are attained at corners
      const Vec3 p = s % 4 == 0 ? Vec3(rng.chance(0.5) ? from.min.x : from.max.x, 0.0f,
                                       rng.chance(0.5) ? from.min.z : from.max.z)
                                : random_point(rng, from);
      const Vec3 q = s % 4 == 0 ? Vec3(rng.chance(0.5) ? to.min.x : to.max.x, 0.0f,
                                       rng.chance(0.5) ? to.min.z : to.max.z)
                                : random_point(rng, to);
      const double yaw = yaw_of(q.x - p.x, q.z - p.z);
      EXPECT_TRUE(range.contains(yaw - 1e-6) || range.contains(yaw + 1e-6)) << trial << " yaw " << yaw;
      near_lo = std::min(near_lo, gap(yaw, range.lo));
      near_hi = std::min(near_hi, gap(yaw, range.hi));
    }
    EXPECT_LT(near_lo, 1e-4) << trial;
    EXPECT_LT(near_hi, 1e-4) << trial;
  }
  EXPECT_GT(disjoint, 100);
}

// Oracle: rays through sampled image points. Their yaws depart from the camera's by at most the
// extent, and the image's corners reach it; looking past the vertical leaves every yaw.
TEST(LiChiangConfigurations, YawHalfExtentAgainstRaysThroughTheImage) {
  Random rng(3);
  for (const float pitch : {0.0f, 20.0f, -45.0f, 58.0f}) {
    Camera camera;
    camera.yaw_deg = 30.0f;
    camera.pitch_deg = pitch;
    const std::optional<double> extent = yaw_half_extent(camera);
    ASSERT_TRUE(extent) << pitch;
    if (pitch == 0.0f) {
      EXPECT_NEAR(*extent, std::atan(std::tan(kPi / 6.0) * camera.aspect), 1e-6);
    }
    const Mat4 inverse = glm::inverse(camera.view_projection());
    double widest = 0.0;
    for (int s = 0; s < 4000; ++s) {
      const float x = s < 4 ? (s % 2 ? 1.0f : -1.0f) : float(rng.uniform(-1.0, 1.0));
      const float y = s < 4 ? (s / 2 ? 1.0f : -1.0f) : float(rng.uniform(-1.0, 1.0));
      const Vec4 h = inverse * Vec4(x, y, 1.0f, 1.0f);
      const Vec3 d = Vec3(h) / h.w - camera.position;
      const double off = gap(yaw_of(d.x, d.z), glm::radians(double(camera.yaw_deg)));
      EXPECT_LE(off, *extent + 1e-4) << pitch;
      widest = std::max(widest, off);
    }
    EXPECT_NEAR(widest, *extent, 1e-3) << pitch;
  }
  Camera up;
  up.pitch_deg = 65.0f;  // 65 + 30 > 90: the image holds the vertical
  EXPECT_FALSE(yaw_half_extent(up));
}

TEST(LiChiangConfigurations, SectorsCoverTheCircleAndWidenByTheMargin) {
  for (int s = 0; s < 8; ++s) {
    const double mid = (s + 0.5) * kPi / 4.0;
    EXPECT_EQ(sector_of(mid, 8), s);
    EXPECT_EQ(sector_of(mid + 2.0 * kPi, 8), s);
    const YawRange own = sector_range(s, 0, 8, 0.0);
    EXPECT_TRUE(own.contains(mid));
    EXPECT_FALSE(own.contains(mid + kPi / 4.0));
    const YawRange wide = sector_range(s, 1, 8, 0.2);
    EXPECT_TRUE(wide.contains(mid + kPi / 8.0 + kPi / 4.0 + 0.19));
    EXPECT_FALSE(wide.contains(mid + kPi / 8.0 + kPi / 4.0 + 0.21));
    EXPECT_TRUE(sector_range(s, 1, 8, std::nullopt).all);
    EXPECT_TRUE(sector_range(s, 1, 8, 2.0).all);  // 3 sectors + 2 × 2 rad ≥ 2π
  }
  EXPECT_TRUE(sector_range(0, 1, 3, 0.0).all);
}

TEST(LiChiangName, ParsesTheFourCasesAndRefusesTheRest) {
  const LiChiangConfig d = parse_lichiang_strategy_name("lichiang");
  EXPECT_EQ(d.cache, LiChiangConfig::Cache::kHybrid);
  EXPECT_EQ(d.prefetch, LiChiangConfig::Prefetch::kRelevance);
  const LiChiangConfig c = parse_lichiang_strategy_name("lichiang:cache=lru,prefetch=one-step,sectors=4");
  EXPECT_EQ(c.cache, LiChiangConfig::Cache::kLru);
  EXPECT_EQ(c.prefetch, LiChiangConfig::Prefetch::kOneStep);
  EXPECT_EQ(c.sectors, 4);
  EXPECT_EQ(parse_lichiang_strategy_name("lichiang:sectors=2").sectors, 2);
  for (const char* bad : {"lichiang:cache=mru", "lichiang:prefetch=two-step", "lichiang:sectors=3.5", "lichiang:sectors=0",
                          "lichiang:speed=1", "lichiang:cache", "lichiang:in_flight=2", "lichiang:cache=none",
                          "lichiang:cache=none,prefetch=one-step"})
    EXPECT_THROW(parse_lichiang_strategy_name(bad), Error) << bad;
}

// t_p on the frame's thread (the seed's frame cycle): a fixed allowance or a frame budget.
TEST(LiChiangName, PrefetchTimeInTheFrameCycle) {
  EXPECT_FALSE(parse_lichiang_strategy_name("lichiang").prefetch_in_frame());
  const LiChiangConfig t = parse_lichiang_strategy_name("lichiang:tp_ms=2.5");
  EXPECT_TRUE(t.prefetch_in_frame());
  EXPECT_EQ(t.tp_ms, 2.5);
  EXPECT_EQ(parse_lichiang_strategy_name("lichiang:cache=lru,prefetch=one-step,frame_ms=100").frame_ms, 100.0);
  for (const char* bad : {"lichiang:tp_ms=-1", "lichiang:tp_ms=x", "lichiang:tp_ms=2,frame_ms=30",
                          "lichiang:cache=lru,prefetch=none,tp_ms=5", "lichiang:cache=none,prefetch=none,frame_ms=5"})
    EXPECT_THROW(parse_lichiang_strategy_name(bad), Error) << bad;
}

class LiChiangSystem : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    inputs_ = new test::SharedInputs(
        "lichiang-city", {"generate city --objects 150 --landmark-fraction 0.2 --seed 6 -o {dir}/city.cwscene",
                          "build {dir}/city.cwscene -o {dir}/city.cww", "build {dir}/city.cwscene -o {dir}/bare.cww",
                          "pvs {dir}/city.cww --engine conservative --cells grid:25",
                          "path {dir}/city.cww --frames 60 --seed 4 -o {dir}/city.path",
                          "path {dir}/city.cww --kind fast --frames 400 --seed 4 -o {dir}/far.path"});
    world_ = inputs_->file("city.cww");
    path_ = inputs_->file("city.path");
    far_path_ = inputs_->file("far.path");
    bare_ = inputs_->file("bare.cww");
  }
  static void TearDownTestSuite() { delete inputs_; }
  static inline test::SharedInputs* inputs_ = nullptr;
  static inline std::string world_, bare_, path_;  // bare_: the same world without sets
  static inline std::string far_path_;             // through several cells
  const test::TempDir out_;                        // this test's outputs
};

// Without sets the strategy names the command; with them, every visible object is drawn, in
// each of the seed's cases, and the union of the neighbours' sets holds the own set.
TEST_F(LiChiangSystem, DrawsEveryVisibleObjectInEachCase) {
  test::CommandResult r = test::run_cellwalk("walk " + bare_ + " --path " + path_ + " --strategy lichiang -o " + out_.file("w0"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("cellwalk pvs"), std::string::npos) << r.output;
  // Sets over a k-d tree: the configurations need a grid, and the message says so.
  const std::string kd = out_.file("kd.cww");
  std::filesystem::copy_file(bare_, kd);
  ASSERT_EQ(test::run_cellwalk("pvs " + kd + " --engine conservative --cells kd:25").exit_code, 0);
  r = test::run_cellwalk("walk " + kd + " --path " + path_ + " --strategy lichiang -o " + out_.file("w0"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--cells grid:"), std::string::npos) << r.output;
  for (const std::string strategy : {"lichiang", "lichiang:neighbours=0", "lichiang:cache=none,prefetch=none",
                                     "lichiang:cache=lru,prefetch=one-step", "lichiang:sectors=1,neighbours=0"}) {
    SCOPED_TRACE(strategy);
    r = test::run_cellwalk("compare " + world_ + " --path " + path_ + " --strategy " + strategy +
                           " --every 3 --width 128 --height 96 --json -o " + out_.file("cmp"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = test::only_run(r);
    ASSERT_TRUE(j.is_object()) << r.output;
    EXPECT_GT(j["visible_objects"].get<uint64_t>(), 0u);
    EXPECT_EQ(j["missed_objects"].get<uint64_t>(), 0u);
  }
}

// In process: a sector keeps less of the cell's set than every direction does, and the
// 1-neighbours' union adds to it.
TEST_F(LiChiangSystem, SectorsDrawLessThanTheCellsSetAndNeighboursMore) {
  const World world(world_);
  const CameraPath path = read_path(path_);
  uint64_t own[3] = {0, 0, 0}, drawn[3] = {0, 0, 0};
  int k = 0;
  for (const std::string name : {"lichiang:sectors=1,neighbours=0,cull=0", "lichiang:neighbours=0,cull=0", "lichiang:cull=0"}) {
    LiChiangStrategy strategy(world, parse_lichiang_strategy_name(name), StrategyOptions{});
    std::vector<DrawItem> items;
    Camera camera;
    for (const PathFrame& f : path.frames) {
      apply(f, camera);
      FrameStats stats;
      strategy.select(camera, items, stats);
    }
    own[k] = strategy.counters().own_ids;
    drawn[k] = strategy.counters().drawn_ids;
    EXPECT_GT(strategy.counters().frames, 0u);
    ++k;
  }
  EXPECT_LT(own[1], own[0]);      // a sector sees less than every direction
  EXPECT_GT(drawn[2], drawn[1]);  // the 1-neighbours add
}

// The four cases under one budget: each walks and holds its share; no cache keeps nothing from
// one frame to the next, so it misses more, hits less and reads more than LRU.
TEST_F(LiChiangSystem, TheFourCasesHoldTheBudget) {
  std::map<std::string, nlohmann::json> runs;
  for (const std::string strategy : {"lichiang:cache=none,prefetch=none", "lichiang:cache=lru,prefetch=none",
                                     "lichiang:cache=lru,prefetch=one-step", "lichiang"}) {
    SCOPED_TRACE(strategy);
    const test::CommandResult r = test::run_cellwalk("walk " + world_ + " --path " + path_ + " --strategy " + strategy +
                                                     " --budget 20 --gpu-budget 1 --width 128 --height 96 --json -o " +
                                                     out_.file("walk"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = test::only_run(r);
    ASSERT_TRUE(j.is_object()) << r.output;
    EXPECT_LE(j["peak_resident_bytes"].get<uint64_t>(), j["strategy_budget_bytes"].get<uint64_t>());
    EXPECT_GT(j["cache_misses"].get<uint64_t>(), 0u);
    runs[strategy] = j;
  }
  const nlohmann::json &none = runs["lichiang:cache=none,prefetch=none"], &lru = runs["lichiang:cache=lru,prefetch=none"];
  EXPECT_GT(none["cache_misses"].get<uint64_t>(), lru["cache_misses"].get<uint64_t>());
  EXPECT_LT(none["cache_hits"].get<uint64_t>(), lru["cache_hits"].get<uint64_t>());
  EXPECT_GT(none["total_bytes_read"].get<uint64_t>(), lru["total_bytes_read"].get<uint64_t>());
}

// Frames by hand (no renderer: every item drawn asks the store): the misses of each frame.
struct InFrameWalk {
  std::vector<uint64_t> misses;
  LiChiangCounters counters;
  uint64_t stall_frames() const { return uint64_t(std::count_if(misses.begin(), misses.end(), [](uint64_t m) { return m > 0; })); }
  uint64_t total() const { return std::accumulate(misses.begin(), misses.end(), uint64_t(0)); }
};

InFrameWalk walk_in_process(const World& world, const CameraPath& path, const std::string& name) {
  LiChiangStrategy strategy(world, parse_lichiang_strategy_name(name), StrategyOptions{});
  InFrameWalk w;
  std::vector<DrawItem> items;
  Camera camera;
  for (const PathFrame& f : path.frames) {
    apply(f, camera);
    FrameStats stats;
    strategy.select(camera, items, stats);
    for (const DrawItem& item : items) EXPECT_NE(strategy.mesh(item, stats), nullptr);
    w.misses.push_back(stats.cache_misses);
  }
  w.counters = strategy.counters();
  return w;
}

// In the seed's cycle, no prefetch time is no prefetching: frame for frame the same misses as
// the case without it. Time enough to load each plan whole leaves fewer misses, and no more
// stall frames.
TEST_F(LiChiangSystem, PrefetchTimeInTheFrameIsWhatPrefetchingGets) {
  const World world(world_);
  const CameraPath path = read_path(far_path_);
  const InFrameWalk none = walk_in_process(world, path, "lichiang:cache=lru,prefetch=none");
  const InFrameWalk zero = walk_in_process(world, path, "lichiang:cache=lru,prefetch=one-step,tp_ms=0");
  EXPECT_EQ(zero.misses, none.misses);
  EXPECT_GT(zero.counters.prefetch_requests, 0u);  // planned, never given time
  EXPECT_GT(none.total(), 0u);
  for (const std::string name : {"lichiang:tp_ms=100000", "lichiang:frame_ms=100000"}) {
    SCOPED_TRACE(name);
    const InFrameWalk ample = walk_in_process(world, path, name);
    EXPECT_GT(ample.counters.prefetch_ms, 0.0);
    EXPECT_LT(ample.total(), none.total());
    EXPECT_LE(ample.stall_frames(), none.stall_frames());
    EXPECT_EQ(ample.misses.front(), none.misses.front());  // nothing is prefetched before the first frame
  }
}

// The bench on a tiny city: its report and CSV are written; with the cache as large as the
// world, the caching cases read each object once and no case passes its budget; without a
// cache every frame reads again. Over the object database, the case without prefetching reads
// what it reads from the world file.
TEST(LiChiangBench, WritesItsReportAndTheCasesBehave) {
  const test::TempDir dir;
  LiChiangBenchParams p;
  p.world_objects = {40};
  p.path_kinds = {"normal"};
  p.frames = 20;
  p.cache_fractions = {1.0};
  p.gpu_mib = 0.0;  // every mesh drawn from a transient buffer: the store serves every frame
  p.width = 64;
  p.height = 48;
  p.out_dir = dir.file("results");
  p.work_dir = dir.file("work");
  p.storages = {"slow", "sqlite"};
  p.read_latency_ms = 0.2;
  p.plot_fractions = {1.0};
  p.plot_tp_ms = {0.0, 1000.0};
  p.command_line = "cellwalk bench lichiang --objects 40";
  const nlohmann::ordered_json s = run_lichiang_bench(p);
  const std::vector<uint8_t> bytes = test::slurp(dir.file("results/lichiang.md"));
  const std::string md(bytes.begin(), bytes.end());
  EXPECT_NE(md.find(p.command_line), std::string::npos);
  EXPECT_NE(md.find("## Target"), std::string::npos);
  EXPECT_GT(std::filesystem::file_size(dir.file("results/lichiang/cases.csv")), 0u);
  EXPECT_EQ(s["over_budget"].get<int>(), 0);
  EXPECT_EQ(s["compared"].get<int>(), 3);  // the page cache, the slow disk, the object database
  EXPECT_EQ(s["tp_walks"].get<int>(), 2);
  EXPECT_GT(std::filesystem::file_size(dir.file("results/lichiang/tp-stalls.svg")), 0u);
  EXPECT_NE(md.find("allowable prefetching time"), std::string::npos);
  EXPECT_NE(md.find("+0.2 ms a read"), std::string::npos);
  const auto& cases = s["40 objects"]["page cache"]["100.0"]["normal"];
  ASSERT_EQ(cases.size(), lichiang_cases().size());
  const uint64_t lru = cases["lichiang:cache=lru,prefetch=none"]["bytes_read"].get<uint64_t>();
  EXPECT_GT(lru, 0u);
  EXPECT_GT(cases["lichiang:cache=none,prefetch=none"]["bytes_read"].get<uint64_t>(), lru);
  EXPECT_EQ(cases["lichiang:cache=none,prefetch=none"]["stall_frames"].get<uint64_t>(), uint64_t(p.frames));
  EXPECT_EQ(cases["lichiang:cache=none,prefetch=none"]["hit_ratio"].get<double>(), 0.0);  // nothing kept across frames
  EXPECT_GT(cases["lichiang:cache=lru,prefetch=none"]["hit_ratio"].get<double>(), 0.5);
  const auto& sqlite = s["40 objects"]["sqlite"]["100.0"]["normal"];
  ASSERT_EQ(sqlite.size(), lichiang_cases().size());
  EXPECT_EQ(sqlite["lichiang:cache=lru,prefetch=none"]["bytes_read"].get<uint64_t>(), lru);
  EXPECT_EQ(sqlite["lichiang:cache=lru,prefetch=none"]["hit_ratio"], cases["lichiang:cache=lru,prefetch=none"]["hit_ratio"]);
  EXPECT_NE(md.find("| sqlite |"), std::string::npos);
}

}  // namespace
}  // namespace cellwalk
