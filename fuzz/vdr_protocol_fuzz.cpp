// libFuzzer target for everything the VDR streaming server and client parse from the network
// (src/systems/vdr/vdr_protocol.cpp; docs/protocol.md, "VDR streaming"): any input must parse or
// give a net::ProtocolError, never a crash, a hang, another exception or an unbounded
// allocation. The first byte picks the message; one that parses must encode back to itself. A
// batch that parses is applied to a small selective mesh, which must accept it or refuse it with
// an Error and stay usable (the client's second line of defence).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "cellwalk/core/error.hpp"
#include "cellwalk/net/frame.hpp"
#include "cellwalk/systems/vdr/selective_mesh.hpp"
#include "cellwalk/systems/vdr/vdr_protocol.hpp"

using namespace cellwalk;
using namespace cellwalk::vdr;

namespace {

void same(const std::vector<uint8_t>& out, std::span<const uint8_t> in) {
  if (out.size() != in.size() || !std::equal(out.begin(), out.end(), in.begin())) std::abort();
}

// A tetrahedron's base mesh: vertices 0..3, triangles 0..3.
void apply(const Batch& b) {
  const Vec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const uint32_t t[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  SelectiveMesh mesh(p, p, t);
  for (const WireOp& op : b.ops) {
    try {
      op.split ? mesh.vsplit(vsplit_op(op)) : mesh.ecol(vsplit_op(op));
    } catch (const Error&) {
    }
  }
  for (uint32_t i : mesh.indices())
    if (i >= mesh.positions().size()) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::span<const uint8_t> in(data + 1, size - 1);
  try {
    switch (data[0] % 5) {
      case 0: same(encode_hello(parse_hello(in)), in); break;
      case 1: same(encode_welcome(parse_welcome(in)), in); break;
      case 2: same(encode_view(parse_view(in)), in); break;
      case 3: {
        const Batch b = parse_batch(in, 64);
        same(encode_batch(b.sequence, b.triangles, b.ops), in);
        apply(b);
        break;
      }
      case 4: parse_error(in); break;
    }
  } catch (const net::ProtocolError&) {
  }
  return 0;
}
