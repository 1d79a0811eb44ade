// Base-colour textures: a scene keeps each as its image file's own bytes (PNG or JPEG, as the
// model had it), so textures stay compressed on disk and in transit and are decoded only where
// they are drawn. Meshes name a texture by its index in the scene's table (Mesh::texture).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cellwalk/scene/mesh.hpp"

namespace cellwalk {

// One entry of a scene's texture table.
struct TextureImage {
  std::string name;              // where it came from (a file name or "glb image 3"), for messages
  std::vector<uint8_t> encoded;  // the PNG or JPEG file's bytes
};

// A decoded texture: RGBA8 texels, rows top-down (texel (0, 0) at uv (0, 0)).
struct Texture {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<Rgba8> texels;
};

// The larger side a decoded texture keeps by default: larger images are halved until they fit,
// which bounds the memory one texture takes while it is decoded and drawn (16 MiB at 2048).
inline constexpr uint32_t kMaxTextureSide = 2048;

enum class TextureFormat { kPng, kJpeg };
struct TextureInfo {
  TextureFormat format = TextureFormat::kPng;
  uint32_t width = 0;
  uint32_t height = 0;
};

// Reads the image's format and size from its header, without decoding it: a PNG or JPEG of 1 to
// 8192 texels a side. Throws Error naming `where` and what to do.
TextureInfo check_texture(std::span<const uint8_t> encoded, std::string_view where);

// Decodes the whole image and discards it: what import checks, so a texture that is accepted
// into a scene also builds into a world. Throws Error naming `where`.
void verify_texture(std::span<const uint8_t> encoded, std::string_view where);

// Decodes to RGBA8 (libpng, libjpeg) and halves (2 × 2 box filter, an odd last row or column
// folded into the one before) until neither side exceeds max_side. Throws Error naming `where`
// for an image that is damaged or not PNG/JPEG.
Texture decode_texture(std::span<const uint8_t> encoded, std::string_view where,
                       uint32_t max_side = kMaxTextureSide);

// A texture's levels of detail as the world keeps them: level 0 is the image file itself, each
// next one the previous halved, down to 1 × 1, re-encoded in the original's format (PNG stays
// lossless; JPEG at quality 90). A renderer reads only the level it draws, so the memory one
// texture takes while it is read and decoded follows what the budget allows it, not the original.
struct TextureLevel {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> encoded;
};
std::vector<TextureLevel> texture_levels(std::span<const uint8_t> encoded, std::string_view where);

}  // namespace cellwalk
