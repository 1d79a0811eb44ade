// PNG output of rendered images, through stb_image_write and the atomic file writer so a failed
// write never leaves a truncated PNG in place of a good one.
#include "cellwalk/render/image.hpp"

#include <string>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"

// Static: other translation units may carry their own copy of stb_image_write.
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

namespace cellwalk {
namespace {

void append_to_string(void* context, void* data, int size) {
  static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
}

}  // namespace

void write_png(const Image& image, const std::string& file) {
  size_t row_bytes = size_t(image.width) * 4;
  if (image.width <= 0 || image.height <= 0 || image.rgba.size() != row_bytes * image.height) {
    fail(file, "cannot write PNG: image is " + std::to_string(image.width) + "x" +
                   std::to_string(image.height) + " with " + std::to_string(image.rgba.size()) +
                   " bytes of pixels");
  }
  // Image rows are bottom-up; a negative stride from the last row writes them top-down.
  const uint8_t* top_row = image.rgba.data() + row_bytes * (image.height - 1);
  std::string png;
  if (!stbi_write_png_to_func(append_to_string, &png, image.width, image.height, 4, top_row,
                              -int(row_bytes))) {
    fail(file, "cannot encode PNG");
  }
  write_file_atomically(file, png);
}

}  // namespace cellwalk
