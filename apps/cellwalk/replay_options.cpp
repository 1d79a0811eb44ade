// Labels of the runs of walk and compare (replay_options.hpp).
#include "replay_options.hpp"

#include <algorithm>

namespace cellwalk::app {

std::vector<ReplayOptions::Run> ReplayOptions::make_runs(const World& world) const {
  for (const std::string& given : strategies)
    if (std::count(strategies.begin(), strategies.end(), given) > 1)
      fail("--strategy " + given, "given twice; each strategy runs once per command");
  std::vector<Run> runs;
  std::vector<std::string> names;
  for (const std::string& given : strategies) {
    runs.push_back({given, "", make_strategy(given, world, strategy_options())});
    names.push_back(runs.back().strategy->name());
  }
  for (size_t i = 0; i < runs.size(); ++i)
    runs[i].label = std::count(names.begin(), names.end(), names[i]) > 1 ? runs[i].name : names[i];
  return runs;
}

}  // namespace cellwalk::app
