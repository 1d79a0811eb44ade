#include "cellwalk/metrics/fidelity.hpp"
#include "cellwalk/metrics/walk_summary.hpp"
#include "cellwalk/runtime/run_budget.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/scene/path_generator.hpp"
#include "cellwalk/store/world.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <nlohmann/json.hpp>

#include "systems/brute/brute.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// A deliberately faulty strategy: brute force that drops one object it should draw.
class DroppingStrategy : public BruteStrategy {
 public:
  DroppingStrategy(const World& world, ObjectId dropped) : BruteStrategy(world, {}, true), dropped_(dropped) {}
  std::string name() const override { return "dropping"; }
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override {
    BruteStrategy::select(camera, items, stats);
    std::erase_if(items, [&](const DrawItem& i) { return i.id == dropped_; });
  }

 private:
  ObjectId dropped_;
};

// Faulty the other way: selects the object but gives it no triangles, as a level whose
// silhouette fell between pixel centres would draw nothing. The item names a level truth never
// draws, so the renderer's cache cannot answer for it.
class HidingStrategy : public BruteStrategy {
 public:
  HidingStrategy(const World& world, ObjectId hidden) : BruteStrategy(world, {}, true), hidden_(hidden) {}
  std::string name() const override { return "hiding"; }
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override {
    BruteStrategy::select(camera, items, stats);
    for (DrawItem& i : items)
      if (i.id == hidden_) i.lod = 1000;
  }
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override {
    return item.id == hidden_ ? &empty_ : BruteStrategy::mesh(item, stats);
  }

 private:
  ObjectId hidden_;
  Mesh empty_;
};

class WalkTest : public ::testing::Test {
 protected:
  void SetUp() override {
    world_ = std::make_unique<World>(test::write_street_world(dir_, 40));
    PathParams p;
    p.frames = 60;
    path_ = generate_path(world_->info().nav, p);
    lens_.aspect = 160.0f / 120.0f;
    context_ = GlContext::headless();
    RenderSettings s;
    s.width = 160;
    s.height = 120;
    renderer_ = std::make_unique<Renderer>(s);
  }
  test::TempDir dir_;
  std::unique_ptr<World> world_;
  CameraPath path_;
  Camera lens_;
  std::unique_ptr<GlContext> context_;
  std::unique_ptr<Renderer> renderer_;
};

TEST_F(WalkTest, BruteMatchesGroundTruthExactly) {
  BruteStrategy brute(*world_, {}, true), truth(*world_, {}, false);
  CompareOptions options;
  options.every = 5;
  auto frames = compare(path_, lens_, brute, truth, *renderer_, options);
  ASSERT_EQ(frames.size(), 12u);
  FidelitySummary s = summarize(frames);
  EXPECT_EQ(s.max_differing_fraction, 0.0);
  EXPECT_EQ(s.missed_objects, 0u);
  EXPECT_EQ(s.max_pixel_error_px, 0.0);
  EXPECT_EQ(s.unmatched_test_pixels + s.unmatched_truth_pixels, 0u);
  EXPECT_GT(s.visible_objects, 12u);  // the frames did show objects
}

TEST_F(WalkTest, DroppedVisibleObjectIsCaught) {
  // Drop the object most often visible in ground truth, found by rendering it.
  BruteStrategy truth(*world_, {}, false);
  Camera cam = lens_;
  apply(path_.frames[0], cam);
  render_frame(truth, *renderer_, cam);
  IdImage ids = renderer_->read_ids();
  std::map<uint32_t, int> area;
  for (uint32_t id : ids.ids)
    if (id != kBackgroundId) ++area[id];
  ASSERT_FALSE(area.empty());
  auto biggest = std::max_element(area.begin(), area.end(), [](auto& a, auto& b) { return a.second < b.second; });
  DroppingStrategy dropping(*world_, biggest->first - 1);
  CompareOptions options;
  options.every = 5;
  const std::vector<FidelityFrame> frames = compare(path_, lens_, dropping, truth, *renderer_, options);
  FidelitySummary s = summarize(frames);
  EXPECT_GT(s.missed_objects, 0u);
  EXPECT_EQ(s.missed_drawn, 0u);  // it was left out, not drawn
  for (const FidelityFrame& f : frames)
    for (uint32_t id : f.missed_ids) EXPECT_EQ(id, biggest->first);
  // The same object drawn with nothing to show is missed as often, and counted as drawn.
  HidingStrategy hiding(*world_, biggest->first - 1);
  const FidelitySummary h = summarize(compare(path_, lens_, hiding, truth, *renderer_, options));
  EXPECT_EQ(h.missed_objects, s.missed_objects);
  EXPECT_EQ(h.missed_drawn, h.missed_objects);
  // Each miss is an object truth shows and the test nowhere: its pixels have no match.
  EXPECT_GE(s.unmatched_truth_pixels, s.missed_objects);
  EXPECT_LT(s.recall, 1.0);
  EXPECT_GT(s.max_differing_fraction, 0.0);
}

// Side by side against one truth per frame, each strategy's frames are what compare() gives it
// alone.
TEST_F(WalkTest, SideBySideMatchesEachAlone) {
  BruteStrategy truth(*world_, {}, false), brute(*world_, {}, true);
  DroppingStrategy dropping(*world_, 3);
  HidingStrategy hiding(*world_, 5);
  CompareOptions options;
  options.every = 7;
  Strategy* const all[] = {&brute, &dropping, &hiding};
  const auto together = compare_side_by_side(path_, lens_, all, truth, *renderer_, options);
  ASSERT_EQ(together.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    const std::vector<FidelityFrame> alone = compare(path_, lens_, *all[k], truth, *renderer_, options);
    ASSERT_EQ(together[k].size(), alone.size());
    for (size_t i = 0; i < alone.size(); ++i) {
      EXPECT_EQ(together[k][i].frame, alone[i].frame);
      EXPECT_EQ(together[k][i].differing_fraction, alone[i].differing_fraction);
      EXPECT_EQ(together[k][i].missed_ids, alone[i].missed_ids);
      EXPECT_EQ(together[k][i].missed_drawn, alone[i].missed_drawn);
      EXPECT_EQ(together[k][i].pixel_error_max_px(), alone[i].pixel_error_max_px());
    }
  }
  EXPECT_GT(summarize(together[1]).missed_objects + summarize(together[2]).missed_objects, 0u);
}

TEST_F(WalkTest, WalkMeasuresEveryFrame) {
  BruteStrategy brute(*world_, {}, true);
  auto frames = walk(path_, lens_, brute, *renderer_);
  ASSERT_EQ(frames.size(), path_.frames.size());
  uint64_t bytes = 0;
  for (const FrameStats& f : frames) {
    EXPECT_GE(f.frame_ms, f.query_ms);
    EXPECT_GT(f.objects, 0u);
    EXPECT_EQ(f.triangles, 12 * f.objects);  // boxes
    bytes += f.bytes_read;
  }
  // With an ample GPU budget each visible object's level 0 is read from the file once.
  std::set<ObjectId> seen;
  Camera cam = lens_;
  for (const PathFrame& f : path_.frames) {
    apply(f, cam);
    for (ObjectId id = 0; id < world_->object_count(); ++id)
      if (Frustum(cam).intersects(world_->object(id).bounds)) seen.insert(id);
  }
  uint64_t expected = 0;
  for (ObjectId id : seen) expected += world_->lod(id, 0).bytes;
  EXPECT_EQ(bytes, expected);
  WalkSummary s = summarize("brute", frames);
  EXPECT_EQ(s.frames, frames.size());
  EXPECT_LE(s.p50_ms, s.p95_ms);
  EXPECT_LE(s.p95_ms, s.max_ms);
}

TEST(CompareImages, CountsDifferencesAndMissedObjects) {
  Image a{2, 1, {10, 10, 10, 255, 20, 20, 20, 255}}, b = a;
  IdImage ia{2, 1, {1, 2}}, ib{2, 1, {1, 0}};
  b.rgba[4] = 30;
  Image diff;
  FidelityFrame f = compare_images(a, ia, b, ib, &diff);
  EXPECT_DOUBLE_EQ(f.differing_fraction, 0.5);
  EXPECT_EQ(f.visible_objects, 2u);
  EXPECT_EQ(f.missed_objects, 1u);
  EXPECT_EQ(diff.rgba[0], 128);
  EXPECT_EQ(diff.rgba[4], 138);
  EXPECT_NEAR(f.psnr_db, 10 * std::log10(255.0 * 255.0 / (100.0 / 6.0)), 1e-9);
  FidelityFrame same = compare_images(a, ia, a, ia, nullptr);
  EXPECT_EQ(same.differing_fraction, 0.0);
  EXPECT_TRUE(std::isinf(same.psnr_db));
  // Pixel 1 differs: truth shows no background for the test's, the test no object 2 for truth's.
  EXPECT_EQ(f.test_to_truth.unmatched, 1u);
  EXPECT_EQ(f.truth_to_test.unmatched, 1u);
  EXPECT_EQ(f.pixel_error_max_px(), 0.0);
  EXPECT_EQ(same.test_to_truth.unmatched + same.truth_to_test.unmatched, 0u);
}

TEST(WalkCommand, WritesCsvAndJson) {
  test::TempDir dir;
  const std::string scene = test::write_street_world(dir, 20);
  auto r = test::run_cellwalk("path " + scene + " --frames 30 -o " + dir.file("p.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cellwalk("walk " + scene + " --path " + dir.file("p.txt") + " --width 96 --height 64 -o " +
                         dir.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream csv(dir.file("out/brute.csv"));
  std::string line;
  int lines = 0;
  while (std::getline(csv, line)) ++lines;
  EXPECT_EQ(lines, 31);
  auto json = nlohmann::json::parse(std::ifstream(dir.file("out/brute.json")));
  EXPECT_EQ(json["frames"], 30);
  EXPECT_GT(json["frame_ms"]["mean"].get<double>(), 0.0);
  EXPECT_GT(json["peak_resident_bytes"].get<uint64_t>(), 0u);
  r = test::run_cellwalk("compare " + scene + " --path " + dir.file("p.txt") +
                         " --every 10 --width 96 --height 64 --json -o " + dir.file("cmp"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"mean_differing_fraction\": 0.0"), std::string::npos) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("cmp/frame0-brute-diff.png")));
}

// Several strategies on one path: each writes its own files, and the table compares them with
// the first. conv draws what brute draws (frustum culling both), so its fidelity is perfect too.
TEST(WalkCommand, SeveralStrategiesSideBySide) {
  test::TempDir dir;
  const std::string world = test::write_street_world(dir, 20);
  auto r = test::run_cellwalk("path " + world + " --frames 20 -o " + dir.file("p.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cellwalk("walk " + world + " --path " + dir.file("p.txt") +
                         " --strategy brute --strategy ground-truth --width 96 --height 64 --json -o " + dir.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto walked = test::json_output(r);
  EXPECT_EQ(walked["schema"], 1);
  EXPECT_EQ(walked["command"], "walk");
  auto all = walked["runs"];
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0]["strategy"], "brute");
  EXPECT_EQ(all[1]["strategy"], "ground-truth");
  EXPECT_EQ(all[1]["frames"], 20);
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/brute.json")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/ground-truth.json")));
  std::ifstream table(dir.file("out/walk.md"));
  std::string header, rule, first, second;
  std::getline(table, header), std::getline(table, rule), std::getline(table, first), std::getline(table, second);
  EXPECT_NE(header.find("speed-up vs brute"), std::string::npos) << header;
  EXPECT_NE(first.find("| brute | "), std::string::npos) << first;
  EXPECT_NE(first.find("1.00×"), std::string::npos) << first;
  EXPECT_NE(second.find("| ground-truth | "), std::string::npos) << second;

  r = test::run_cellwalk("compare " + world + " --path " + dir.file("p.txt") +
                         " --strategy brute --strategy conv --every 5 --width 96 --height 64 --json -o " + dir.file("cmp"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto fidelities = test::json_output(r)["runs"];
  ASSERT_EQ(fidelities.size(), 2u);
  EXPECT_EQ(fidelities[1]["strategy"], "conv");
  for (const auto& run : fidelities) {
    EXPECT_EQ(run["pixel_error"]["max_px"], 0.0) << run;
    EXPECT_EQ(run["pixel_error"]["unmatched_truth_pixels"], 0) << run;
  }
  std::ifstream fidelity(dir.file("cmp/compare.md"));
  std::string line;
  int perfect = 0;
  while (std::getline(fidelity, line))
    if (line.find(" 0 of ") != std::string::npos && line.find("inf (identical)") != std::string::npos &&
        line.find("| 0.00 (0 %) | 0.00 (0 %) |") != std::string::npos)
      ++perfect;
  EXPECT_EQ(perfect, 2) << r.output;
}

// Two runs never share files or a row: REVIEW's name leaves its settings out, so two REVIEWs
// are labelled by the text given; the same text twice is refused before anything runs.
TEST(WalkCommand, RunsWithTheSameNameAreToldApart) {
  test::TempDir dir;
  const std::string world = dir.file("city.cww");  // built by the command, so it has an R-tree
  auto r = test::run_cellwalk("generate city --objects 40 --seed 2 -o " + dir.file("city.cwscene"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cellwalk("build " + dir.file("city.cwscene") + " -o " + world);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cellwalk("path " + world + " --frames 10 -o " + dir.file("p.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cellwalk("walk " + world + " --path " + dir.file("p.txt") +
                         " --strategy review:depth=60 --strategy review:depth=80 --width 96 --height 64 -o " + dir.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/review:depth=60.csv")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/review:depth=80.csv")));
  std::ifstream table(dir.file("out/walk.md"));
  const std::string text((std::istreambuf_iterator<char>(table)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("| review:depth=80 |"), std::string::npos) << text;

  r = test::run_cellwalk("walk " + world + " --path " + dir.file("p.txt") +
                         " --strategy brute --strategy conv --strategy brute --width 96 --height 64 -o " + dir.file("twice"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--strategy brute: given twice"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("twice/brute.csv"))) << "refused before any run";
  r = test::run_cellwalk("walk " + world + " --path " + dir.file("p.txt") +
                         " --strategy brute --strategy nonsense --width 96 --height 64 -o " + dir.file("bad"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad/brute.csv"))) << "a bad name fails before any run";
}

// The hard budget end to end: a walk given a budget well below the world's geometry reports
// that budget and a peak resident size under it in its summary JSON.
TEST(WalkCommand, BudgetFarBelowTheWorldHoldsInTheSummary) {
  test::TempDir dir;
  const std::string world = test::write_street_world(dir, 40);
  World opened(world);
  uint64_t largest = 0, total = 0;
  for (ObjectId id = 0; id < opened.object_count(); ++id) {
    Mesh m = opened.decode_level(id, 0, opened.read_level(id, 0));
    largest = std::max<uint64_t>(largest, sizeof(Mesh) + m.byte_size());
    total += sizeof(Mesh) + m.byte_size();
  }
  // The strategy's part of the process budget (run_budget.hpp) holds the directory and two levels.
  const uint64_t strategy_budget = opened.resident_bytes() + 2 * largest;
  ASSERT_LT(strategy_budget, opened.resident_bytes() + total / 3) << "the world is too small for the test";
  const uint64_t budget = uint64_t(double(strategy_budget + 40 * kBytesPerFrame) / (1.0 - kGpuBudgetShare)) + 1;
  auto r = test::run_cellwalk("path " + world + " --frames 40 -o " + dir.file("p.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const double budget_mib = double(budget) / 1048576.0;
  r = test::run_cellwalk("walk " + world + " --path " + dir.file("p.txt") + " --budget " +
                         std::to_string(budget_mib) + " --width 96 --height 64 -o " + dir.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto json = nlohmann::json::parse(std::ifstream(dir.file("out/brute.json")));
  const uint64_t reported = json["budget_bytes"].get<uint64_t>();
  EXPECT_NEAR(double(reported), double(budget), 1024.0);
  EXPECT_GT(json["peak_resident_bytes"].get<uint64_t>(), 0u);
  const uint64_t strategy_part = json["strategy_budget_bytes"].get<uint64_t>();
  EXPECT_LE(json["peak_resident_bytes"].get<uint64_t>(), strategy_part);
  EXPECT_EQ(strategy_part + json["gpu_budget_bytes"].get<uint64_t>() + 40 * kBytesPerFrame, reported)
      << "the parts add up to the budget";
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/walk.md"))) << "one strategy gets its table too";
  // The budget binds: the same walk without one holds more than it.
  r = test::run_cellwalk("walk " + world + " --path " + dir.file("p.txt") + " --width 96 --height 64 -o " + dir.file("free"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto free = nlohmann::json::parse(std::ifstream(dir.file("free/brute.json")));
  EXPECT_GT(free["peak_resident_bytes"].get<uint64_t>(), strategy_part);
}

TEST(WalkCommand, BadPathFileGivesOneClearLine) {
  test::TempDir dir;
  const std::string scene = test::write_street_world(dir, 4);
  std::ofstream(dir.file("p.txt")) << "# cellwalk path 1\n0 1 2\n";
  auto r = test::run_cellwalk("walk " + scene + " --path " + dir.file("p.txt"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find(dir.file("p.txt") + ":2: expected 6 numbers"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace cellwalk
