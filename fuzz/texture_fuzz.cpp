// libFuzzer target for texture decoding (PNG and JPEG through stb_image, then halving): any
// input must give a texture or a cellwalk::Error, never a crash or an allocation past the
// size limit check_texture enforces.
#include <cstddef>
#include <cstdint>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/texture.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const cellwalk::Texture t = cellwalk::decode_texture({data, size}, "fuzz.png", 64);
    if (t.texels.size() != size_t(t.width) * t.height || t.width > 64 || t.height > 64) __builtin_trap();
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
