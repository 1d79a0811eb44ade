// libFuzzer target for the camera path reader.
#include "cellwalk/core/error.hpp"
#include "cellwalk/core/camera_path.hpp"
#include "file_fuzz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = cellwalk::fuzz::write_input(data, size, ".path");
  try {
    cellwalk::read_path(path);
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
