// libFuzzer target for the PLY reader: any input must give objects or a cellwalk::Error,
// never a crash, a hang, another exception or an allocation the input cannot justify.
#include <cstddef>
#include <cstdint>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    cellwalk::parse_model(cellwalk::ModelFormat::kPly, {data, size}, "fuzz.ply").objects;
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
