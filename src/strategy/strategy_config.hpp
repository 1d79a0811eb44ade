// Strategy names with settings, "base[:key=value,...]" (e.g. "visual:eta=0.001,cache=64"):
// the one parser behind every strategy whose name carries its configuration.
#pragma once

#include <functional>
#include <initializer_list>
#include <cstdint>
#include <string>
#include <utility>

namespace cellwalk {

// One key=value of a strategy name; its checks fail with one line naming the whole name.
struct StrategySetting {
  std::string name;  // the whole strategy name, for errors
  std::string key, value;

  // The value as a number in [lo, hi]; fails on anything else.
  double number(double lo, double hi) const;
  // The value as a whole number in [lo, hi]; fails on anything else.
  int whole(int lo, int hi) const;
  // The value as HOST:PORT (port 1–65535); fails naming `what_to_give` (what the value should be).
  std::pair<std::string, uint16_t> host_port(const std::string& what_to_give) const;
  // Fails unless the value is one of `options`.
  void choice(std::initializer_list<const char*> options) const;
  // Fails: the key is not a setting of this strategy; `known` lists the ones that are.
  [[noreturn]] void unknown(const std::string& known) const;
};

// The part of `name` before its ':' (all of it without one).
std::string strategy_base(const std::string& name);

// Calls `apply` on each setting after the ':' of `name`, in order (none without a ':').
// Fails on an item that is not key=value.
void for_each_strategy_setting(const std::string& name, const std::function<void(const StrategySetting&)>& apply);

}  // namespace cellwalk
