// libFuzzer target for the object database reader (src/store/object_database.cpp, docs/format.md
// "Object database"): a good database of tests/data/seeds/cube.cww, edited by the input, must
// open and read every level as the world file's bytes, or give a cellwalk::Error; never a crash,
// never other bytes. Input: 5-byte edits, each a little-endian u32 offset (modulo the file's size)
// and a byte XORed in there; a zero byte truncates the file at that offset instead.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/object_database.hpp"
#include "cellwalk/store/world.hpp"
#include "file_fuzz.hpp"

namespace {

struct Fixture {
  std::unique_ptr<cellwalk::World> world;
  std::vector<uint8_t> good;  // the database's bytes

  Fixture() {
    world = std::make_unique<cellwalk::World>(std::string(CELLWALK_SOURCE_DIR) +
                                              "/tests/data/seeds/cube.cww");
    const std::string path = "/tmp/cellwalk-fuzz-good-" + std::to_string(getpid()) + ".sqlite";
    cellwalk::build_object_database(*world, path);
    const auto size = std::filesystem::file_size(path);
    good.resize(size);
    FILE* f = std::fopen(path.c_str(), "rb");
    if (!f || std::fread(good.data(), 1, size, f) != size) std::abort();
    std::fclose(f);
    std::filesystem::remove(path);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cellwalk;
  static const Fixture fixture;
  std::vector<uint8_t> bytes = fixture.good;
  for (size_t at = 0; at + 5 <= size && !bytes.empty(); at += 5) {
    uint32_t offset = 0;
    std::memcpy(&offset, data + at, 4);
    offset %= bytes.size();
    if (data[at + 4] == 0)
      bytes.resize(offset);
    else
      bytes[offset] ^= data[at + 4];
  }
  const std::string path = fuzz::write_input(bytes.data(), bytes.size(), ".sqlite");
  try {
    const ObjectDatabase db(*fixture.world, path);
    for (ObjectId id = 0; id < fixture.world->object_count(); ++id)
      for (uint32_t level = 0; level < fixture.world->object(id).lod_count; ++level)
        if (db.read_level(id, level) != fixture.world->read_level(id, level)) std::abort();
  } catch (const Error&) {
  }
  return 0;
}
