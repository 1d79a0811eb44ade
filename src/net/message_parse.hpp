// Helpers for the parsers of network messages (docs/protocol.md): every parser reads through a
// ByteReader, which throws Error on a short buffer; on the network that is a ProtocolError, which
// closes the session that sent it.
#pragma once

#include <string>

#include "cellwalk/net/frame.hpp"
#include "core/bytes.hpp"

namespace cellwalk::net {

// Runs `body`, turning any failure but a ProtocolError into one naming the message.
template <typename F>
auto parsing(const char* message, F&& body) {
  try {
    return body();
  } catch (const ProtocolError&) {
    throw;
  } catch (const std::exception& e) {
    throw ProtocolError(std::string("a malformed ") + message + " message: " + e.what());
  }
}

// A message must be read to its last byte.
inline void expect_end(const ByteReader& r, const char* message) {
  if (r.remaining() != 0)
    throw ProtocolError(std::string("a ") + message + " message with " + std::to_string(r.remaining()) + " bytes too many");
}

}  // namespace cellwalk::net
