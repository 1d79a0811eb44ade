// Labels of the runs of walk and compare (replay_options.hpp).
#include "replay_options.hpp"

#include <algorithm>

namespace cellwalk::app {

std::vector<std::string> ReplayOptions::labels(const World& world) const {
  std::vector<std::string> names;
  for (const std::string& given : strategies) names.push_back(make_strategy(given, world, strategy_options())->name());
  std::vector<std::string> out;
  for (size_t i = 0; i < strategies.size(); ++i) {
    if (std::count(strategies.begin(), strategies.end(), strategies[i]) > 1)
      fail("--strategy " + strategies[i], "given twice; each strategy runs once per command");
    out.push_back(std::count(names.begin(), names.end(), names[i]) > 1 ? strategies[i] : names[i]);
  }
  return out;
}

}  // namespace cellwalk::app
