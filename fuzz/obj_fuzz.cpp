// libFuzzer target for the OBJ readers: any input must give objects (read whole) or a mesh (its
// geometry alone, as the streamed import reads it) or a cellwalk::Error, never a crash, a hang,
// another exception or an allocation the input cannot justify.
#include <cstddef>
#include <cstdint>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"
#include "scene/readers.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    cellwalk::parse_model(cellwalk::ModelFormat::kObj, {data, size}, "fuzz.obj").objects;
  } catch (const cellwalk::Error&) {
  }
  try {
    cellwalk::detail::MeshCollector geometry;
    cellwalk::detail::read_obj_geometry({data, size}, "fuzz.obj", geometry);
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
