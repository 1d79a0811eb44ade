// Names of REVIEW's configurations (HDoV thesis §4.4: Optimal, NC, NP, BOX) and their settings
// (digest §5.3 defaults: k = 0.8, 1 MB index cache, DPLRU with α = β = γ = 1/3).
#include <cstdlib>
#include <sstream>

#include "cellwalk/error.hpp"
#include "cellwalk/review.hpp"

namespace cellwalk {
namespace {

double number(const std::string& name, const std::string& key, const std::string& value, double lo, double hi) {
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || !(v >= lo && v <= hi))
    fail("strategy \"" + name + "\"", key + "=" + value + " must be a number in [" + std::to_string(lo) + ", " +
                                          std::to_string(hi) + "]");
  return v;
}

void apply(ReviewConfig& c, const std::string& name, const std::string& key, const std::string& value) {
  auto choice = [&](std::initializer_list<const char*> options) {
    for (const char* o : options)
      if (value == o) return;
    std::string all;
    for (const char* o : options) all += std::string(all.empty() ? "" : " | ") + o;
    fail("strategy \"" + name + "\"", key + "=" + value + " must be one of " + all);
  };
  if (key == "k") c.k = number(name, key, value, 0, 100);
  else if (key == "sf") c.scale_factor = number(name, key, value, 1, 100);
  else if (key == "depth") c.depth = number(name, key, value, 1, 1e6);
  else if (key == "cache") c.index_cache_bytes = uint64_t(number(name, key, value, 0.004, 1e5) * 1048576.0);
  else if (key == "buffer") c.object_buffer_bytes = uint64_t(number(name, key, value, 0, 1e6) * 1048576.0);
  else if (key == "trigger") c.trigger = number(name, key, value, 0, 1);
  else if (key == "fps") c.fps = number(name, key, value, 0.001, 1e4);
  else if (key == "policy") {
    choice({"dplru", "lru"});
    c.policy = value == "lru" ? RTreeCacheOptions::Policy::kLru : RTreeCacheOptions::Policy::kDistancePriorityLru;
  } else if (key == "prefetch") {
    choice({"sync", "background"});
    c.background_prefetch = value == "background";
  } else if (key == "cull") {
    choice({"exact", "none"});
    c.cull = value == "exact";
  } else {
    fail("strategy \"" + name + "\"", "unknown setting '" + key +
                                          "'; known: k, sf, depth, cache, policy, buffer, prefetch, trigger, fps, cull");
  }
}

}  // namespace

bool is_review_strategy_name(const std::string& name) { return name.rfind("review", 0) == 0; }

ReviewConfig parse_review_strategy_name(const std::string& name) {
  const size_t colon = name.find(':');
  const std::string base = name.substr(0, colon);
  ReviewConfig c;
  if (base == "review") c.variant = ReviewConfig::Variant::kOptimal;
  else if (base == "review-nc") c.variant = ReviewConfig::Variant::kNoCache;
  else if (base == "review-np") c.variant = ReviewConfig::Variant::kNoPrefetch;
  else if (base == "review-box") c.variant = ReviewConfig::Variant::kBox;
  else fail("strategy \"" + name + "\"", "unknown; REVIEW's configurations are review, review-nc, review-np, review-box");
  if (colon == std::string::npos) return c;
  std::stringstream settings(name.substr(colon + 1));
  for (std::string item; std::getline(settings, item, ',');) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos) fail("strategy \"" + name + "\"", "setting '" + item + "' is not key=value");
    apply(c, name, item.substr(0, eq), item.substr(eq + 1));
  }
  return c;
}

}  // namespace cellwalk
