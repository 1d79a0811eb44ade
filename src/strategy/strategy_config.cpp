// Strategy names with settings, "base[:key=value,...]": see strategy_config.hpp.
#include "strategy/strategy_config.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "cellwalk/core/error.hpp"

namespace cellwalk {

double StrategySetting::number(double lo, double hi) const {
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || !(v >= lo && v <= hi))
    fail("strategy \"" + name + "\"", key + "=" + value + " must be a number in [" + std::to_string(lo) + ", " +
                                          std::to_string(hi) + "]");
  return v;
}

int StrategySetting::whole(int lo, int hi) const {
  const double v = number(lo, hi);
  if (v != std::floor(v)) fail("strategy \"" + name + "\"", key + "=" + value + " is not a whole number");
  return int(v);
}

std::pair<std::string, uint16_t> StrategySetting::host_port(const std::string& what_to_give) const {
  const size_t colon = value.rfind(':');
  if (colon == std::string::npos || colon == 0)
    fail("strategy \"" + name + "\"", key + "=" + value + " must be " + what_to_give);
  return {value.substr(0, colon), uint16_t(StrategySetting{name, key + " port", value.substr(colon + 1)}.whole(1, 65535))};
}

void StrategySetting::choice(std::initializer_list<const char*> options) const {
  for (const char* o : options)
    if (value == o) return;
  std::string all;
  for (const char* o : options) all += std::string(all.empty() ? "" : " | ") + o;
  fail("strategy \"" + name + "\"", key + "=" + value + " must be one of " + all);
}

void StrategySetting::unknown(const std::string& known) const {
  fail("strategy \"" + name + "\"", "unknown setting '" + key + "'; known: " + known);
}

std::string strategy_base(const std::string& name) { return name.substr(0, name.find(':')); }

void for_each_strategy_setting(const std::string& name, const std::function<void(const StrategySetting&)>& apply) {
  const size_t colon = name.find(':');
  if (colon == std::string::npos) return;
  std::stringstream settings(name.substr(colon + 1));
  for (std::string item; std::getline(settings, item, ',');) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos) fail("strategy \"" + name + "\"", "setting '" + item + "' is not key=value");
    apply({name, item.substr(0, eq), item.substr(eq + 1)});
  }
}

}  // namespace cellwalk
