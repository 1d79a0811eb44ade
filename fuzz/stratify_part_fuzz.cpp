// libFuzzer target for the part and checkpoint files of `stratify build --shard` (BakePart;
// docs/format.md, "Stratify parts"). The base is a real part — records of far fields of 8²
// texels made without GL — edited by the input: when its first byte is 0 the rest of the input is
// the file itself; otherwise a truncation (u16, modulo the file's size + 1) and then (u16 offset,
// u8 xor) edits. Reading the part and every record it indexes must give data or a
// cellwalk::Error, never a crash, another exception, or an id past the objects.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/stratified/bake_log.hpp"
#include "edits.hpp"
#include "far_field_pattern.hpp"
#include "store/checkpoint_file.hpp"

namespace {

using namespace cellwalk;
using namespace cellwalk::stratified;

constexpr int kResolution = 8;
constexpr uint64_t kObjects = 50;
constexpr float kBox = 40.0f;

struct Base {
  std::string dir = "/tmp/cellwalk-fuzz-stratify-part-" + std::to_string(getpid());
  std::vector<uint8_t> part;

  Base() {
    std::filesystem::create_directories(dir);
    const std::string path = dir + "/base.part";
    {
      BakeLog log(path, 0x1234, 1, 3);
      StratifiedSizes sizes;
      for (const CellId c : {3u, 4u, 9u}) log.append(c, encode_far_field(fuzz::far_field_pattern(c, kObjects, kBox, kResolution), kBox, sizes));
    }
    part = read_checkpoint_file(path);
  }
  ~Base() {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const Base base;
  if (size == 0) return 0;
  static const std::string path = base.dir + "/input.part";
  const std::vector<uint8_t> bytes = fuzz::edited(base.part, data, size, data[0] == 0);
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!bytes.empty()) std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
  try {
    const BakePart part(path);
    for (const CellId c : part.cells()) {
      for (const FaceImage& face : part.far_field(c, kBox, kResolution, kObjects).faces)
        for (const uint32_t id : face.ids.ids)
          if (id > kObjects) std::abort();
    }
  } catch (const Error&) {
  }
  return 0;
}
