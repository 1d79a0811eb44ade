// The frame every cellwalk network message travels in (docs/protocol.md, "Frames"): a 12-byte
// little-endian header — magic "CWNP", protocol version, message type, two zero bytes, payload
// length — then the payload. The network layer's one parser of untrusted bytes: every check is
// made before anything is allocated.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace cellwalk::net {

constexpr size_t kFrameHeaderBytes = 12;
constexpr uint8_t kProtocolVersion = 1;

// A peer broke the protocol: the session that sent it is closed with this reason.
class ProtocolError : public std::runtime_error {
 public:
  explicit ProtocolError(const std::string& reason) : std::runtime_error(reason) {}
};

struct FrameHeader {
  uint8_t type = 0;
  uint32_t length = 0;  // payload bytes
};

// REQUIRES: header.size() == kFrameHeaderBytes. Throws ProtocolError for another magic or
// version, non-zero reserved bytes, or a payload longer than `max_payload`.
FrameHeader parse_frame_header(std::span<const uint8_t> header, uint32_t max_payload);

// The frame of one message.
std::vector<uint8_t> make_frame(uint8_t type, std::span<const uint8_t> payload);

}  // namespace cellwalk::net
