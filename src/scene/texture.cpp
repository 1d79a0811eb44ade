// Base-colour textures decoded with stb_image (scene/texture.hpp).
#include "cellwalk/scene/texture.hpp"

#include <algorithm>
#include <climits>
#include <cstring>
#include <memory>
#include <utility>

#include "cellwalk/core/error.hpp"

// Static: other translation units (tinygltf's, if it ever decodes) may carry their own copy.
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_NO_STDIO
#include <stb/stb_image.h>

namespace cellwalk {
namespace {

constexpr int kMaxDecodedSide = 8192;  // refused above this (256 MiB decoded): a damaged header, or a poster

int checked_length(std::span<const uint8_t> encoded, std::string_view where) {
  if (encoded.empty()) fail(where, "texture image is empty");
  if (encoded.size() > size_t(INT_MAX)) fail(where, "texture image is larger than 2 GiB");
  return int(encoded.size());
}

// The source texels [begin, end) along one axis that output texel i averages: two, and the
// odd last one folded into the last output texel.
std::pair<uint32_t, uint32_t> source_span(uint32_t i, uint32_t out_n, uint32_t in_n) {
  const uint32_t begin = std::min(i * 2, in_n - 1);
  const uint32_t end = i + 1 == out_n ? in_n : std::min(in_n, i * 2 + 2);
  return {begin, end};
}

// One halving by a box filter.
Texture halve(const Texture& in) {
  Texture out;
  out.width = std::max(1u, in.width / 2);
  out.height = std::max(1u, in.height / 2);
  out.texels.resize(size_t(out.width) * out.height);
  for (uint32_t y = 0; y < out.height; ++y) {
    const auto [y0, y1] = source_span(y, out.height, in.height);
    for (uint32_t x = 0; x < out.width; ++x) {
      const auto [x0, x1] = source_span(x, out.width, in.width);
      uint32_t sum[4] = {0, 0, 0, 0};
      for (uint32_t sy = y0; sy < y1; ++sy)
        for (uint32_t sx = x0; sx < x1; ++sx)
          for (int c = 0; c < 4; ++c) sum[c] += (in.texels[size_t(sy) * in.width + sx] >> (8 * c)) & 0xff;
      const uint32_t n = (y1 - y0) * (x1 - x0);
      out.texels[size_t(y) * out.width + x] =
          rgba8(uint8_t(sum[0] / n), uint8_t(sum[1] / n), uint8_t(sum[2] / n), uint8_t(sum[3] / n));
    }
  }
  return out;
}

}  // namespace

void check_texture(std::span<const uint8_t> encoded, std::string_view where) {
  int w = 0, h = 0, channels = 0;
  if (!stbi_info_from_memory(encoded.data(), checked_length(encoded, where), &w, &h, &channels))
    fail(where, std::string("texture is not a PNG or JPEG cellwalk can read (") + stbi_failure_reason() +
                    "); convert it to PNG or JPEG");
  if (w <= 0 || h <= 0 || w > kMaxDecodedSide || h > kMaxDecodedSide)
    fail(where, "texture is " + std::to_string(w) + " x " + std::to_string(h) +
                    " texels; cellwalk reads up to " + std::to_string(kMaxDecodedSide) + " a side: scale it down");
}

Texture decode_texture(std::span<const uint8_t> encoded, std::string_view where, uint32_t max_side) {
  check_texture(encoded, where);
  int w = 0, h = 0, channels = 0;
  std::unique_ptr<stbi_uc, void (*)(void*)> pixels(
      stbi_load_from_memory(encoded.data(), int(encoded.size()), &w, &h, &channels, 4), stbi_image_free);
  if (!pixels) fail(where, std::string("texture cannot be decoded (") + stbi_failure_reason() + "); the image is damaged");
  Texture t;
  t.width = uint32_t(w);
  t.height = uint32_t(h);
  t.texels.resize(size_t(w) * size_t(h));
  std::memcpy(t.texels.data(), pixels.get(), t.byte_size());
  pixels.reset();
  while (t.width > std::max(1u, max_side) || t.height > std::max(1u, max_side)) t = halve(t);
  return t;
}

}  // namespace cellwalk
