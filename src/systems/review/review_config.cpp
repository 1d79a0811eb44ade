// Names of REVIEW's configurations (HDoV thesis §4.4: Optimal, NC, NP, BOX) and their settings
// (digest §5.3 defaults: k = 0.8, 1 MB index cache, DPLRU with α = β = γ = 1/3).
#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/review/review.hpp"
#include "strategy/strategy_config.hpp"

namespace cellwalk {
namespace {

void apply(ReviewConfig& c, const StrategySetting& s) {
  const std::string& key = s.key;
  if (key == "k") c.k = s.number(0, 100);
  else if (key == "sf") c.scale_factor = s.number(1, 100);
  else if (key == "depth") c.depth = s.number(1, 1e6);
  else if (key == "cache") c.index_cache_bytes = uint64_t(s.number(0.004, 1e5) * 1048576.0);
  else if (key == "buffer") c.object_buffer_bytes = uint64_t(s.number(0, 1e6) * 1048576.0);
  else if (key == "trigger") c.trigger = s.number(0, 1);
  else if (key == "fps") c.fps = s.number(0.001, 1e4);
  else if (key == "policy") {
    s.choice({"dplru", "lru"});
    c.policy = s.value == "lru" ? RTreeCacheOptions::Policy::kLru : RTreeCacheOptions::Policy::kDistancePriorityLru;
  } else if (key == "prefetch") {
    s.choice({"sync", "background"});
    c.background_prefetch = s.value == "background";
  } else if (key == "cull") {
    s.choice({"exact", "none"});
    c.cull = s.value == "exact";
  } else {
    s.unknown("k, sf, depth, cache, policy, buffer, prefetch, trigger, fps, cull");
  }
}

}  // namespace

bool is_review_strategy_name(const std::string& name) { return name.rfind("review", 0) == 0; }

ReviewConfig parse_review_strategy_name(const std::string& name) {
  const std::string base = strategy_base(name);
  ReviewConfig c;
  if (base == "review") c.variant = ReviewConfig::Variant::kOptimal;
  else if (base == "review-nc") c.variant = ReviewConfig::Variant::kNoCache;
  else if (base == "review-np") c.variant = ReviewConfig::Variant::kNoPrefetch;
  else if (base == "review-box") c.variant = ReviewConfig::Variant::kBox;
  else fail("strategy \"" + name + "\"", "unknown; REVIEW's configurations are review, review-nc, review-np, review-box");
  for_each_strategy_setting(name, [&](const StrategySetting& s) { apply(c, s); });
  return c;
}

}  // namespace cellwalk
