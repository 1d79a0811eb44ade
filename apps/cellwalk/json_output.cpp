#include "json_output.hpp"

#include <cstdio>

#include "cellwalk/core/error.hpp"

namespace cellwalk::app {

void print_json(const std::string& command, const nlohmann::ordered_json& body) {
  if (!body.is_object()) fail("print_json", "the body of " + command + "'s JSON must be an object");
  nlohmann::ordered_json j = {{"schema", kJsonSchema}, {"command", command}};
  for (auto it = body.begin(); it != body.end(); ++it) j[it.key()] = it.value();
  std::printf("%s\n", j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace).c_str());
}

}  // namespace cellwalk::app
