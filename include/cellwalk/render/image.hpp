// Images the renderer produces: colour (RGBA8) and per-pixel object ids.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace cellwalk {

// Rows are stored bottom-up as OpenGL reads them; write_png flips to top-down.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba;  // 4 bytes per pixel
};

// Object id + 1 per pixel; 0 means background (no object).
struct IdImage {
  int width = 0;
  int height = 0;
  std::vector<uint32_t> ids;
};

constexpr uint32_t kBackgroundId = 0;

// Writes to a temporary name and renames. Throws Error naming the file on failure.
void write_png(const Image& image, const std::string& file);

}  // namespace cellwalk
