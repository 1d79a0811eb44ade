// How the fuzz targets over a real file or section turn an input into the bytes they read:
// `raw` (the target's choice from the first byte) takes the rest of the input as the bytes;
// otherwise the base is truncated (u16 at data[1..2], modulo its size + 1) and then edited by
// (u16 offset, u8 xor) triples. Real bases reach deep into the parser; raw inputs reach the rest.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cellwalk::fuzz {

// REQUIRES: size >= 1.
inline std::vector<uint8_t> edited(const std::vector<uint8_t>& base, const uint8_t* data, size_t size, bool raw) {
  if (raw) return {data + 1, data + size};
  std::vector<uint8_t> out = base;
  if (size >= 3) out.resize((data[1] | size_t(data[2]) << 8) % (base.size() + 1));
  for (size_t i = 3; i + 2 < size && !out.empty(); i += 3)
    out[(data[i] | size_t(data[i + 1]) << 8) % out.size()] ^= data[i + 2];
  return out;
}

}  // namespace cellwalk::fuzz
