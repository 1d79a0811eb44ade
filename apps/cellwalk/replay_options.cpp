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

ReplayOptions::Run ReplayOptions::make_run(const std::string& given, const World& world, const RunBudget& budget,
                                           std::vector<std::string>& labels_used) const {
  Run run{"", make_strategy(given, world, strategy_options(budget))};
  const std::string name = run.strategy->name();
  run.label = std::count(labels_used.begin(), labels_used.end(), name) > 0 ? given : name;
  labels_used.push_back(run.label);
  return run;
}

}  // namespace cellwalk::app
