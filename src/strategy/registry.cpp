// make_strategy: the one place that knows every strategy by name.
#include "cellwalk/error.hpp"
#include "cellwalk/strategy.hpp"
#include "strategy/brute.hpp"

namespace cellwalk {

std::vector<std::string> strategy_names() { return {"brute", "ground-truth"}; }

std::unique_ptr<Strategy> make_strategy(const std::string& name, const World& world,
                                        const StrategyOptions& options) {
  if (name == "brute") return std::make_unique<BruteStrategy>(world, options, true);
  if (name == "ground-truth") return std::make_unique<BruteStrategy>(world, options, false);
  std::string known;
  for (const auto& n : strategy_names()) known += (known.empty() ? "" : ", ") + n;
  fail("strategy \"" + name + "\"", "unknown; choose one of " + known);
}

}  // namespace cellwalk
