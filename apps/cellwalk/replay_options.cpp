// The runs of walk and compare (replay_options.hpp).
#include "replay_options.hpp"

#include <algorithm>

namespace cellwalk::app {

void ReplayOptions::check_strategies() const {
  for (const std::string& given : strategies) {
    if (std::count(strategies.begin(), strategies.end(), given) > 1)
      fail("--strategy " + given, "given twice; each strategy runs once per command");
    check_strategy_name(given);
  }
}

namespace {

// "review" of "review:depth=60", "visual" of "visual": runs of one family may share a name.
std::string family(const std::string& given) { return given.substr(0, given.find(':')); }

}  // namespace

ReplayOptions::Run ReplayOptions::make_run(const std::string& given, const World& world, const RunBudget& budget,
                                           std::vector<std::string>& labels_used) const {
  Run run{"", make_strategy(given, world, strategy_options(budget))};
  const auto same_family = std::count_if(strategies.begin(), strategies.end(),
                                         [&](const std::string& s) { return family(s) == family(given); });
  const std::string name = run.strategy->name();
  run.label = same_family > 1 || std::count(labels_used.begin(), labels_used.end(), name) > 0 ? given : name;
  labels_used.push_back(run.label);
  return run;
}

}  // namespace cellwalk::app
