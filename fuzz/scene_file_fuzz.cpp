// libFuzzer target for the scene file reader: the trailer, footer, table and every object
// record must give objects or a cellwalk::Error, never a crash or another exception.
#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "file_fuzz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = cellwalk::fuzz::write_input(data, size, ".cwscene");
  try {
    cellwalk::SceneReader scene(path);
    for (cellwalk::ObjectId id = 0; id < scene.object_count() && id < 64; ++id) scene.read_object(id);
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
