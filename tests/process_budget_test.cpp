// The memory budget bounds the process (docs/design.md, "Memory"): `walk --budget B` never has
// more resident than B plus the fixed baseline it reports, as the kernel measures it from
// outside (wait4's peak RSS) and inside (VmHWM) — for every strategy, on worlds of two sizes —
// and the baseline does not grow with the world.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace cellwalk {
namespace {

constexpr double kBudgetMib = 12;

// A generated city with degrees of visibility and its HDoV-tree, so every strategy can walk it.
struct BudgetWorld {
  std::string world, path;
};

BudgetWorld make_world(const test::TempDir& dir, int objects) {
  const std::string name = dir.file("city" + std::to_string(objects));
  for (const std::string& command :
       {"generate city --objects " + std::to_string(objects) + " --seed 5 -o " + name + ".cwscene",
        "build " + name + ".cwscene -o " + name + ".cww",
        "pvs " + name + ".cww --engine dov --cells grid:200 --dov-resolution 16",
        "visual-build " + name + ".cww",
        "path " + name + ".cww --frames 60 --seed 2 -o " + name + ".path"}) {
    const test::CommandResult r = test::run_cellwalk(command);
    EXPECT_EQ(r.exit_code, 0) << command << "\n" << r.output;
  }
  return {name + ".cww", name + ".path"};
}

struct Measured {
  uint64_t outside = 0, inside = 0, baseline = 0, budget = 0;
};

Measured walk_under_budget(const test::TempDir& dir, const BudgetWorld& w, const std::string& strategy) {
  const std::string out = dir.file("walk-" + std::to_string(std::hash<std::string>()(w.world + strategy)));
  const test::CommandResult r =
      test::run_cellwalk("walk " + w.world + " --path " + w.path + " --strategy " + strategy + " --budget " +
                         std::to_string(kBudgetMib) + " --width 160 --height 120 --json -o " + out);
  EXPECT_EQ(r.exit_code, 0) << strategy << "\n" << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output.substr(r.output.find('{')), nullptr, false);
  if (j.is_discarded()) {
    ADD_FAILURE() << "no JSON summary: " << r.output;
    return {};
  }
  return {r.max_rss_bytes, j["peak_rss_bytes"].get<uint64_t>(), j["baseline_rss_bytes"].get<uint64_t>(),
          j["budget_bytes"].get<uint64_t>()};
}

TEST(ProcessBudget, WalksStayWithinBudgetPlusBaselineForEveryStrategyAndTheBaselineDoesNotGrow) {
  test::TempDir dir;
  const BudgetWorld small = make_world(dir, 120), large = make_world(dir, 480);
  std::map<std::string, uint64_t> baselines;
  for (const BudgetWorld* w : {&small, &large}) {
    for (const std::string strategy : {"brute", "conv", "hdov-vsc", "hdov-pb", "review", "visual", "visual:maxdov=1e-9"}) {
      const Measured m = walk_under_budget(dir, *w, strategy);
      SCOPED_TRACE(w->world + " " + strategy);
      EXPECT_NEAR(double(m.budget), kBudgetMib * 1048576.0, 1.0);
      EXPECT_GT(m.baseline, 0u);
      EXPECT_LE(m.outside, m.budget + m.baseline) << "outside: " << m.outside / 1048576.0 << " MiB, baseline "
                                                  << m.baseline / 1048576.0 << " MiB";
      EXPECT_LE(m.inside, m.budget + m.baseline) << "inside: " << m.inside / 1048576.0 << " MiB";
      baselines[w->world] = std::max(baselines[w->world], m.baseline);
    }
  }
  // The baseline is measured before the world opens: four times the objects, the same baseline.
  EXPECT_NEAR(double(baselines[large.world]), double(baselines[small.world]), 4.0 * 1048576.0);
  // The budget binds: without one, brute on the larger world holds more than the budget above
  // its baseline.
  const test::CommandResult free = test::run_cellwalk("walk " + large.world + " --path " + large.path +
                                                      " --width 160 --height 120 --json -o " + dir.file("free"));
  ASSERT_EQ(free.exit_code, 0) << free.output;
  EXPECT_GT(free.max_rss_bytes, uint64_t(kBudgetMib * 1048576.0) + baselines[large.world]);
}

}  // namespace
}  // namespace cellwalk
