// The one error type of cellwalk. Every failure a user can cause (a bad file, a bad argument,
// a full disk) is reported as an Error whose message is one line: where, what, and when it
// helps, what to do. Nothing else is thrown across layer boundaries.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace cellwalk {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Throws Error("<where>: <what>"). `where` names the file, section, line or offset.
[[noreturn]] void fail(std::string_view where, std::string_view what);

// Prints "cellwalk: warning: <where>: <what>" as one line on stderr, for damage cellwalk
// recovers from by itself (e.g. a checkpoint it discards); the run goes on.
void warn(std::string_view where, std::string_view what);

}  // namespace cellwalk
