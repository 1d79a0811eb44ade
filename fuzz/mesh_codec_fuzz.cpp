// libFuzzer target for the mesh codec's decoder: any input must give a valid mesh or a
// cellwalk::Error, never a crash, a hang, another exception or an unbounded allocation.
#include <cstddef>
#include <cstdint>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/mesh_codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  cellwalk::DecodeLimits limits;
  limits.max_mesh_bytes = size_t(64) << 20;  // well under libFuzzer's 2 GB malloc limit
  try {
    cellwalk::decode_mesh({data, size}, "fuzz", limits);
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
