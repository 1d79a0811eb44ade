#include "cellwalk/core/error.hpp"

namespace cellwalk {

void fail(std::string_view where, std::string_view what) {
  std::string message;
  message.reserve(where.size() + what.size() + 2);
  message.append(where).append(": ").append(what);
  throw Error(message);
}

}  // namespace cellwalk
