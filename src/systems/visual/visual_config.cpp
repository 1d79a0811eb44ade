// The settings of strategy "visual" (HDoV thesis §5.8: η, the storage scheme, the node cache
// and its policy), parsed from "visual[:key=value,...]".
#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/visual/visual_strategy.hpp"
#include "strategy/strategy_config.hpp"

namespace cellwalk {

bool is_visual_strategy_name(const std::string& name) { return name == "visual" || name.rfind("visual:", 0) == 0; }

VisualConfig parse_visual_strategy_name(const std::string& name) {
  if (!is_visual_strategy_name(name)) fail("strategy \"" + name + "\"", "not a VISUAL name (visual[:key=value,...])");
  VisualConfig c;
  for_each_strategy_setting(name, [&](const StrategySetting& s) {
    if (s.key == "eta") c.eta = s.number(0, 1);
    else if (s.key == "scheme") c.scheme = parse_vpage_scheme(s.value);
    else if (s.key == "cache") c.cache.pages = uint64_t(s.number(0, 1e7));
    else if (s.key == "policy") c.cache.policy = parse_hdov_cache_policy(s.value);
    else if (s.key == "maxdov") c.max_dov = s.number(1e-9, 1);
    else if (s.key == "tree") c.tree_file = s.value;
    else s.unknown("eta, scheme, cache, policy, maxdov, tree");
  });
  return c;
}

}  // namespace cellwalk
