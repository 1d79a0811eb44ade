// Base-colour textures (scene/texture.hpp): PNG through libpng's simplified API, JPEG through
// libjpeg(-turbo); both are fuzzed upstream (OSS-Fuzz), and every size is checked here before
// anything is allocated.
#include "cellwalk/scene/texture.hpp"

#include <jpeglib.h>
#include <png.h>

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <utility>

#include "cellwalk/core/error.hpp"

namespace cellwalk {
namespace {

constexpr uint32_t kMaxDecodedSide = 8192;  // refused above this (256 MiB decoded): a damaged header, or a poster
constexpr int kJpegQuality = 90;

bool is_png(std::span<const uint8_t> b) { return b.size() >= 8 && png_sig_cmp(b.data(), 0, 8) == 0; }
bool is_jpeg(std::span<const uint8_t> b) { return b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF; }

void check_size(uint32_t width, uint32_t height, std::string_view where) {
  if (width == 0 || height == 0 || width > kMaxDecodedSide || height > kMaxDecodedSide)
    fail(where, "texture is " + std::to_string(width) + " x " + std::to_string(height) +
                    " texels; cellwalk reads 1 to " + std::to_string(kMaxDecodedSide) + " a side: scale it down");
}

// --- PNG ---------------------------------------------------------------------------------------

struct PngImage {
  png_image image{};
  PngImage() { image.version = PNG_IMAGE_VERSION; }
  ~PngImage() { png_image_free(&image); }
};

void begin_png(PngImage& png, std::span<const uint8_t> b, std::string_view where) {
  if (!png_image_begin_read_from_memory(&png.image, b.data(), b.size()))
    fail(where, std::string("PNG cannot be read (") + png.image.message + "); the image is damaged");
  check_size(png.image.width, png.image.height, where);
}

Texture decode_png(std::span<const uint8_t> b, std::string_view where) {
  PngImage png;
  begin_png(png, b, where);
  png.image.format = PNG_FORMAT_RGBA;
  Texture t;
  t.width = png.image.width;
  t.height = png.image.height;
  t.texels.resize(size_t(t.width) * t.height);
  if (!png_image_finish_read(&png.image, nullptr, t.texels.data(), 0, nullptr))
    fail(where, std::string("PNG cannot be decoded (") + png.image.message + "); the image is damaged");
  return t;
}

std::vector<uint8_t> encode_png(const Texture& t, std::string_view where) {
  PngImage png;
  png.image.width = t.width;
  png.image.height = t.height;
  png.image.format = PNG_FORMAT_RGBA;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&png.image, nullptr, &size, 0, t.texels.data(), 0, nullptr))
    fail(where, std::string("PNG cannot be written: ") + png.image.message);
  std::vector<uint8_t> out(size);
  if (!png_image_write_to_memory(&png.image, out.data(), &size, 0, t.texels.data(), 0, nullptr))
    fail(where, std::string("PNG cannot be written: ") + png.image.message);
  out.resize(size);
  return out;
}

// --- JPEG --------------------------------------------------------------------------------------

// libjpeg reports errors through a callback that must not return: it jumps back to the setjmp
// in the function that called libjpeg, which then throws. Only C objects live between the two.
struct JpegErrors {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void jpeg_error_exit(j_common_ptr info) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  (*info->err->format_message)(info, errors->message);
  std::longjmp(errors->jump, 1);
}
void jpeg_quiet(j_common_ptr, int) {}  // warnings (a truncated scan) decode what there is

// A progressive JPEG of thousands of scans costs a pass over the image each: real ones have
// about ten, so more than kMaxJpegScans is refused (libjpeg-turbo's own fuzzers do the same).
constexpr int kMaxJpegScans = 500;
void jpeg_count_scans(j_common_ptr info) {
  if (info->is_decompressor) {
    auto* d = reinterpret_cast<j_decompress_ptr>(info);
    if (d->input_scan_number > kMaxJpegScans) {
      std::snprintf(reinterpret_cast<JpegErrors*>(info->err)->message, JMSG_LENGTH_MAX, "more than %d scans",
                    kMaxJpegScans);
      std::longjmp(reinterpret_cast<JpegErrors*>(info->err)->jump, 1);
    }
  }
}

void init_errors(JpegErrors& errors) {
  jpeg_std_error(&errors.manager);
  errors.manager.error_exit = jpeg_error_exit;
  errors.manager.emit_message = jpeg_quiet;
  errors.message[0] = '\0';
}

// Decodes into `t` (declared by the caller, so no C++ object lives across the jump); returns
// false with errors.message set on failure. With `header_only`, reads the size alone.
bool jpeg_decode(std::span<const uint8_t> b, Texture& t, bool header_only, JpegErrors& errors) {
  jpeg_decompress_struct info;
  init_errors(errors);
  info.err = &errors.manager;
  if (setjmp(errors.jump)) {
    jpeg_destroy_decompress(&info);
    return false;
  }
  jpeg_create_decompress(&info);
  jpeg_progress_mgr progress{};
  progress.progress_monitor = jpeg_count_scans;
  info.progress = &progress;
  info.mem->max_memory_to_use = 512L << 20;
  jpeg_mem_src(&info, b.data(), static_cast<unsigned long>(b.size()));
  jpeg_read_header(&info, TRUE);
  t.width = info.image_width;
  t.height = info.image_height;
  if (header_only || t.width == 0 || t.height == 0 || t.width > kMaxDecodedSide || t.height > kMaxDecodedSide) {
    jpeg_destroy_decompress(&info);
    return true;
  }
  info.out_color_space = JCS_EXT_RGBA;
  jpeg_start_decompress(&info);
  t.texels.resize(size_t(t.width) * t.height);
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = reinterpret_cast<JSAMPROW>(&t.texels[size_t(info.output_scanline) * t.width]);
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return true;
}

Texture decode_jpeg(std::span<const uint8_t> b, std::string_view where) {
  Texture t;
  JpegErrors errors;
  if (!jpeg_decode(b, t, false, errors))
    fail(where, std::string("JPEG cannot be decoded (") + errors.message + "); the image is damaged");
  check_size(t.width, t.height, where);
  return t;
}

bool jpeg_encode(const Texture& t, unsigned char*& buffer, unsigned long& size, JpegErrors& errors) {
  jpeg_compress_struct info;
  init_errors(errors);
  info.err = &errors.manager;
  if (setjmp(errors.jump)) {
    jpeg_destroy_compress(&info);
    return false;
  }
  jpeg_create_compress(&info);
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = t.width;
  info.image_height = t.height;
  info.input_components = 4;
  info.in_color_space = JCS_EXT_RGBA;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, kJpegQuality, TRUE);
  jpeg_start_compress(&info, TRUE);
  while (info.next_scanline < info.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(reinterpret_cast<const JSAMPLE*>(&t.texels[size_t(info.next_scanline) * t.width]));
    jpeg_write_scanlines(&info, &row, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  return true;
}

std::vector<uint8_t> encode_jpeg(const Texture& t, std::string_view where) {
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  JpegErrors errors;
  const bool ok = jpeg_encode(t, buffer, size, errors);
  const std::unique_ptr<unsigned char, void (*)(void*)> owned(buffer, std::free);
  if (!ok) fail(where, std::string("JPEG cannot be written: ") + errors.message);
  return {buffer, buffer + size};
}

// --- levels ------------------------------------------------------------------------------------

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

TextureInfo check_texture(std::span<const uint8_t> encoded, std::string_view where) {
  if (encoded.empty()) fail(where, "texture image is empty");
  TextureInfo info;
  if (is_png(encoded)) {
    PngImage png;
    begin_png(png, encoded, where);
    info = {TextureFormat::kPng, png.image.width, png.image.height};
  } else if (is_jpeg(encoded)) {
    Texture t;
    JpegErrors errors;
    if (!jpeg_decode(encoded, t, true, errors))
      fail(where, std::string("JPEG cannot be read (") + errors.message + "); the image is damaged");
    check_size(t.width, t.height, where);
    info = {TextureFormat::kJpeg, t.width, t.height};
  } else {
    fail(where, "texture is neither a PNG nor a JPEG; convert it to one of them");
  }
  return info;
}

void verify_texture(std::span<const uint8_t> encoded, std::string_view where) {
  check_texture(encoded, where).format == TextureFormat::kPng ? decode_png(encoded, where) : decode_jpeg(encoded, where);
}

Texture decode_texture(std::span<const uint8_t> encoded, std::string_view where, uint32_t max_side) {
  Texture t = check_texture(encoded, where).format == TextureFormat::kPng ? decode_png(encoded, where)
                                                                          : decode_jpeg(encoded, where);
  while (t.width > std::max(1u, max_side) || t.height > std::max(1u, max_side)) t = halve(t);
  return t;
}

std::vector<TextureLevel> texture_levels(std::span<const uint8_t> encoded, std::string_view where) {
  const TextureInfo info = check_texture(encoded, where);
  std::vector<TextureLevel> levels;
  levels.push_back({info.width, info.height, {encoded.begin(), encoded.end()}});
  Texture t = decode_texture(encoded, where, kMaxDecodedSide);
  while (t.width > 1 || t.height > 1) {
    t = halve(t);
    levels.push_back({t.width, t.height, info.format == TextureFormat::kPng ? encode_png(t, where) : encode_jpeg(t, where)});
  }
  return levels;
}

}  // namespace cellwalk
