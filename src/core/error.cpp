#include "cellwalk/core/error.hpp"

#include <cstdio>

namespace cellwalk {

void fail(std::string_view where, std::string_view what) {
  std::string message;
  message.reserve(where.size() + what.size() + 2);
  message.append(where).append(": ").append(what);
  throw Error(message);
}

void warn(std::string_view where, std::string_view what) {
  std::fprintf(stderr, "cellwalk: warning: %.*s: %.*s\n", int(where.size()), where.data(), int(what.size()),
               what.data());
}

}  // namespace cellwalk
