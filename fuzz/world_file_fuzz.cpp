// libFuzzer target for the world file reader: opening, the directory, the object names, every
// level's pages and their decoding must give data or a cellwalk::Error, never a crash or another
// exception.
#include "cellwalk/core/error.hpp"
#include "cellwalk/store/world.hpp"
#include "file_fuzz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = cellwalk::fuzz::write_input(data, size, ".cww");
  try {
    cellwalk::World world(path);
    world.object_names();
    for (cellwalk::ObjectId id = 0; id < world.object_count() && id < 64; ++id)
      for (uint32_t level = 0; level < world.object(id).lod_count; ++level)
        world.decode_level(id, level, world.read_level(id, level));
    world.file().verify();
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
