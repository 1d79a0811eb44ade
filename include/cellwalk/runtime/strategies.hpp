// Every strategy by name: the one place above all the systems that knows them
// (src/runtime/strategies.cpp).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

// Names accepted by make_strategy, for --help and errors.
std::vector<std::string> strategy_names();

// Throws the Error make_strategy would for an unknown name or malformed settings, without
// opening anything: lets a command check every --strategy before its first run.
void check_strategy_name(const std::string& name);

// REQUIRES: `world` outlives the strategy. Throws Error on an unknown name.
std::unique_ptr<Strategy> make_strategy(const std::string& name, const World& world,
                                        const StrategyOptions& options);

}  // namespace cellwalk
