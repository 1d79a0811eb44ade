// The one --json convention of every command (docs/json.md): one JSON object on standard
// output, {"schema": kJsonSchema, "command": "<subcommand>", ...}; the file a command writes is
// "output", the file it reads "input"; commands that run several strategies (walk, compare)
// give "runs": a list, whatever the number of runs.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace cellwalk::app {

// Raised when a key changes meaning or goes away; a key added keeps the version.
inline constexpr int kJsonSchema = 1;

// Prints {"schema", "command"} followed by the keys of `body` (an object). Strings that are not
// valid UTF-8 (file names) are written with U+FFFD in place of the bad bytes.
void print_json(const std::string& command, const nlohmann::ordered_json& body);

}  // namespace cellwalk::app
