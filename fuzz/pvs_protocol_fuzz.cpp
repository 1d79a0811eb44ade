// libFuzzer target for everything the PVS streaming server and client parse from the network
// (src/net/frame.cpp, src/systems/pvs_stream/pvs_protocol.cpp; docs/protocol.md): any input must
// parse or give a net::ProtocolError, never a crash, a hang, another exception or an unbounded
// allocation. The first byte picks the parser; a message that parses must encode back to itself.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "cellwalk/net/frame.hpp"
#include "cellwalk/systems/pvs_stream/pvs_protocol.hpp"

using namespace cellwalk;

namespace {

template <typename T, typename Encode>
void round_trip(const T& value, Encode encode, std::span<const uint8_t> in) {
  const std::vector<uint8_t> out = encode(value);
  if (out.size() != in.size() || !std::equal(out.begin(), out.end(), in.begin())) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::span<const uint8_t> in(data + 1, size - 1);
  try {
    switch (data[0] % 10) {
      case 0:
        if (in.size() == net::kFrameHeaderBytes) net::parse_frame_header(in, 1u << 20);
        break;
      case 1: pvs_stream::parse_hello(in); break;
      case 2: round_trip(pvs_stream::parse_welcome(in), pvs_stream::encode_welcome, in); break;
      case 3: round_trip(pvs_stream::parse_fetch(in, 1000, 5000), pvs_stream::encode_fetch, in); break;
      case 4: round_trip(pvs_stream::parse_rows(in), pvs_stream::encode_rows, in); break;
      case 5: round_trip(pvs_stream::parse_object(in), pvs_stream::encode_object, in); break;
      case 6: round_trip(pvs_stream::parse_done(in), pvs_stream::encode_done, in); break;
      case 7: pvs_stream::parse_error(in); break;
      case 8: pvs_stream::parse_catalog_request(in); break;
      case 9: round_trip(pvs_stream::parse_catalog(in), pvs_stream::encode_catalog, in); break;
    }
  } catch (const net::ProtocolError&) {
  }
  return 0;
}
