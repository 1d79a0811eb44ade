#include "experiments/disk_order/disk_order_report.hpp"
#include "experiments/vlod/vlod_report.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "test_support.hpp"

namespace cellwalk {
namespace {

std::string slurp(const std::filesystem::path& file) {
  const std::vector<uint8_t> bytes = test::slurp(file.string());
  return std::string(bytes.begin(), bytes.end());
}

// The whole bench at a tiny scale: every report file is written and the figures hold what
// must hold whatever the machine: brute is ground truth, vlod draws fewer triangles than the
// frustum alone holds, a stored Δ is no larger than its bitmask, the TSP order has no more runs.
TEST(VlodBench, WritesReportWithSaneFigures) {
  const test::TempDir dir;
  VlodBenchParams p;
  p.city_objects = 60;
  p.plant_units = 1;
  p.scale_objects = {60, 120};
  p.path_kinds = {"normal"};
  p.frames = 24;
  p.width = 160;
  p.height = 120;
  p.fidelity_every = 6;
  p.tightness_cells = 2;
  p.out_dir = dir.file("results");
  p.work_dir = dir.file("work");
  p.command_line = "cellwalk bench vlod --city-objects 60";
  const nlohmann::ordered_json s = run_vlod_bench(p);

  const std::filesystem::path out = p.out_dir;
  const std::string md = slurp(out / "vlod.md");
  for (const char* heading : {"## Walkthroughs", "## Storage", "## Coherence", "## Scale", "## Tightness", "## Precompute"})
    EXPECT_NE(md.find(heading), std::string::npos) << heading;
  EXPECT_NE(md.find(p.command_line), std::string::npos);
  for (const char* file : {"walks.csv", "storage.csv", "coherence.csv", "delta-histogram.csv", "scale.csv",
                           "tightness.csv", "precompute.csv", "triangles-0.svg", "triangles-1.svg"})
    EXPECT_GT(std::filesystem::file_size(out / "vlod" / file), 0u) << file;

  ASSERT_EQ(s["worlds"].size(), 2u);
  for (const auto& w : s["worlds"]) {
    const auto& walks = w["walks"]["normal"];
    ASSERT_EQ(walks.size(), 6u);  // brute, conv, review, vlod ×2 bounds, vlod cull=0
    EXPECT_EQ(walks[0]["label"], "brute");
    EXPECT_EQ(walks[0]["missed_objects"], 0u);
    EXPECT_EQ(walks[0]["pixel_error_max_px"], 0.0);
    EXPECT_GT(walks[0]["visible_objects"].get<uint64_t>(), 0u);
    for (const auto& r : walks) {
      const std::string label = r["label"];
      if (label.rfind("vlod", 0) != 0 || label.find("cull=0") != std::string::npos) continue;
      EXPECT_LT(r["triangles_per_frame"].get<double>(), walks[0]["triangles_per_frame"].get<double>()) << label;
    }
    for (const auto& v : w["vlod"]) {
      EXPECT_GT(v["cells"].get<uint64_t>(), 0u);
      EXPECT_LE(v["delta_bytes"].get<uint64_t>(), v["bitmask_bytes"].get<uint64_t>());
      EXPECT_LE(v["runs_tsp_order"].get<uint64_t>(), v["runs_world_order"].get<uint64_t>());
      EXPECT_GE(v["runs_morton_order"].get<uint64_t>(), v["runs_tsp_order"].get<uint64_t>() > 0 ? 1u : 0u);
    }
  }
  ASSERT_EQ(s["scale"].size(), 2u);
  EXPECT_EQ(s["scale"][0]["vlod_over_smallest"], 1.0);
  // The city of the scale table not walked above has its Δ storage in the report too.
  ASSERT_EQ(s["scale_storage"].size(), 1u);
  EXPECT_LE(s["scale_storage"][0]["vlod"][0]["delta_bytes"].get<uint64_t>(),
            s["scale_storage"][0]["vlod"][0]["bitmask_bytes"].get<uint64_t>());
  EXPECT_EQ(md.find("Still running"), std::string::npos);
}

// The smallest bench the budget tests need: one city, one plant, one scale city, one path,
// one bound; the caller sets the budget.
VlodBenchParams budget_params(const test::TempDir& dir, int frames, int width, int height) {
  VlodBenchParams p;
  p.city_objects = 60;
  p.plant_units = 1;
  p.scale_objects = {60};
  p.path_kinds = {"normal"};
  p.pixel_errors = {1.0};
  p.frames = frames;
  p.width = width;
  p.height = height;
  p.fidelity_every = 6;
  p.tightness_cells = 1;
  p.out_dir = dir.file("results");
  p.work_dir = dir.file("work");
  return p;
}

// A strategy the budget cannot hold is a row saying so, and the bench goes on.
TEST(VlodBench, ARefusedBudgetIsARowNotAnAbort) {
  const test::TempDir dir;
  VlodBenchParams p = budget_params(dir, 12, 96, 72);
  p.budget_fraction = 0.001;
  p.min_budget_mib = 1;  // REVIEW's R-tree alone needs more
  const nlohmann::ordered_json s = run_vlod_bench(p);
  uint64_t refused = 0;
  for (const auto& w : s["worlds"])
    for (const auto& r : w["walks"]["normal"]) refused += r.contains("refused") ? 1 : 0;
  EXPECT_GT(refused, 0u);
  EXPECT_NE(slurp(std::filesystem::path(p.out_dir) / "vlod.md").find("refused: "), std::string::npos);
  // The scale table's runs under the same budget: figures or the reason, never an abort.
  ASSERT_EQ(s["scale"].size(), 1u);
  EXPECT_TRUE(s["scale"][0].contains("refused") || s["scale"][0].contains("vlod_ms")) << s["scale"][0].dump();
}

// With a budget nothing fits in, every run of every table is a refusal row, and the report
// is written whole.
TEST(VlodBench, NothingFitsAndTheReportStillComesOut) {
  const test::TempDir dir;
  VlodBenchParams p = budget_params(dir, 6, 64, 48);
  p.budget_fraction = 0.0;
  p.min_budget_mib = 0.01;  // 10 KiB: not even a world's directory
  const nlohmann::ordered_json s = run_vlod_bench(p);
  for (const auto& w : s["worlds"])
    for (const auto& r : w["walks"]["normal"]) EXPECT_TRUE(r.contains("refused")) << r.dump();
  ASSERT_EQ(s["scale"].size(), 1u);
  EXPECT_TRUE(s["scale"][0].contains("refused")) << s["scale"][0].dump();
  const std::string md = slurp(std::filesystem::path(p.out_dir) / "vlod.md");
  EXPECT_NE(md.find("## Precompute"), std::string::npos);
  EXPECT_EQ(md.find("Still running"), std::string::npos);
}

// Table 1 at small sizes: every run is in the report, beside the seed's row where the seed has
// one, and the order found never has more runs than the random one it started from.
TEST(DiskOrderBench, WritesTable1) {
  const test::TempDir dir;
  DiskOrderBenchParams p;
  p.sizes = {120, 500};
  p.max_iterations = 300;
  p.max_seconds = 1;
  p.out_dir = dir.file("results");
  p.command_line = "cellwalk bench disk-order --sizes 120 500";
  const nlohmann::ordered_json s = run_disk_order_bench(p);
  ASSERT_EQ(s["runs"].size(), 8u);  // 2 sizes × short/long rows × exact/sampled lists
  for (const auto& r : s["runs"]) {
    EXPECT_GT(r["imp1"].get<double>(), 1.0);
    EXPECT_GE(r["imp_final"].get<double>(), r["imp1"].get<double>());
    EXPECT_GE(r["runs_final"].get<uint64_t>(), 1u);
  }
  const std::string md = slurp(std::filesystem::path(p.out_dir) / "disk-order.md");
  EXPECT_NE(md.find(p.command_line), std::string::npos);
  EXPECT_NE(md.find("| 500 | short | exact |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 3.1 | 6.28 |"), std::string::npos) << "the seed's row for 500 columns";
  EXPECT_GT(std::filesystem::file_size(std::filesystem::path(p.out_dir) / "disk-order" / "table1.csv"), 0u);
}

}  // namespace
}  // namespace cellwalk
