#include "experiments/store/store_report.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "test_support.hpp"

namespace cellwalk {
namespace {

std::string slurp(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The whole bench at a tiny scale: every report file is written and the figures are sane.
TEST(StoreBench, WritesReportWithSaneFigures) {
  const test::TempDir dir;
  StoreBenchParams params;
  params.objects = 60;
  params.path_frames = 40;
  params.io_rounds = 2;
  params.random_reads = 32;
  params.sequential_bytes = 4 << 20;
  params.budget_fractions = {0.05, 0.2, 0.5, 1.0};
  params.out_dir = dir.file("results");
  params.work_dir = dir.file("work");
  params.command_line = "cellwalk bench store --objects 60";
  const nlohmann::ordered_json s = run_store_bench(params);

  const std::filesystem::path out = params.out_dir;
  const std::string md = slurp(out / "store.md");
  for (const char* heading :
       {"## Build", "## Reads", "## Decode", "## Cache policies", "## Reading"}) {
    EXPECT_NE(md.find(heading), std::string::npos) << heading;
  }
  EXPECT_NE(md.find(params.command_line), std::string::npos);
  for (const char* file :
       {"build.csv", "io.csv", "decode.csv", "cache.csv", "summary.json", "hit_ratio.svg"}) {
    EXPECT_GT(std::filesystem::file_size(out / "store" / file), 0u) << file;
  }

  EXPECT_EQ(s["build"]["objects"], 60u);
  EXPECT_GT(s["build"]["peak_rss_bytes"].get<uint64_t>(), 0u);
  EXPECT_GT(s["build"]["build_to_simplify"].get<double>(), 0.0);
  EXPECT_GT(s["decode"]["decode_to_memcpy"].get<double>(), 0.0);
  for (const auto& r : s["io"]["results"]) EXPECT_GT(r["throughput_to_raw"].get<double>(), 0.0);

  const auto& cache = s["cache"];
  const double bound = cache["hit_ratio_bound"];
  const uint64_t largest = cache["largest_item_bytes"];
  std::map<std::string, std::vector<std::pair<uint64_t, double>>> by_policy;
  for (const auto& r : cache["results"]) {
    const double h = r["hit_ratio"];
    EXPECT_GE(h, 0.0);
    EXPECT_LE(h, bound + 1e-12);  // no policy beats first-request misses
    by_policy[r["policy"]].push_back({r["budget_bytes"], h});
  }
  EXPECT_EQ(by_policy.size(), 5u);
  for (const auto& [policy, points] : by_policy) {
    // With the whole working set nothing is evicted: every policy meets the bound.
    EXPECT_NEAR(points.back().second, bound, 1e-12) << policy;
  }
  // LRU keeps the longest prefix of its recency stack that fits, so with every item admitted
  // (budget >= the largest item) a larger budget holds a superset: hits never fall. Smaller
  // budgets turn large items away uncached, which breaks that inclusion, so they are not checked.
  double previous = 0.0;
  for (const auto& [budget, h] : by_policy["LRU"]) {
    if (budget < largest) continue;
    EXPECT_GE(h, previous - 1e-12) << budget;
    previous = h;
  }
}

}  // namespace
}  // namespace cellwalk
