// The network layer's frame (docs/protocol.md, "Frames").
#include "cellwalk/net/frame.hpp"

#include <cstring>

namespace cellwalk::net {
namespace {
constexpr uint8_t kMagic[4] = {'C', 'W', 'N', 'P'};
}

FrameHeader parse_frame_header(std::span<const uint8_t> h, uint32_t max_payload) {
  if (h.size() != kFrameHeaderBytes) throw ProtocolError("a frame header is 12 bytes");
  if (std::memcmp(h.data(), kMagic, 4) != 0) throw ProtocolError("not a cellwalk frame (bad magic)");
  if (h[4] != kProtocolVersion)
    throw ProtocolError("protocol version " + std::to_string(h[4]) + ", this cellwalk speaks " +
                        std::to_string(kProtocolVersion));
  if (h[6] != 0 || h[7] != 0) throw ProtocolError("reserved header bytes are not zero");
  FrameHeader out;
  out.type = h[5];
  std::memcpy(&out.length, h.data() + 8, 4);
  if (out.length > max_payload)
    throw ProtocolError("a message of " + std::to_string(out.length) + " bytes, more than the " +
                        std::to_string(max_payload) + " allowed");
  return out;
}

std::vector<uint8_t> make_frame(uint8_t type, std::span<const uint8_t> payload) {
  std::vector<uint8_t> f(kFrameHeaderBytes + payload.size());
  std::memcpy(f.data(), kMagic, 4);
  f[4] = kProtocolVersion;
  f[5] = type;
  const uint32_t n = uint32_t(payload.size());
  std::memcpy(f.data() + 8, &n, 4);
  if (!payload.empty()) std::memcpy(f.data() + kFrameHeaderBytes, payload.data(), payload.size());
  return f;
}

}  // namespace cellwalk::net
