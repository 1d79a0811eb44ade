// Text overlay through stb_easy_font (Sean Barrett, public domain): quads to triangles.
#include "render/text_overlay.hpp"

#include <algorithm>
#include <string>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"  // the header's helpers we do not call
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop

namespace cellwalk::render {
namespace {

// stb_easy_font's own estimate is ~270 bytes per character; a margin keeps long glyphs whole
// (it stops at the end of the buffer rather than overflow).
constexpr size_t kBufferBytesPerCharacter = 512;

}  // namespace

void append_text(float x, float y, std::string_view text, Rgba8 color, float scale,
                 std::vector<OverlayVertex>& out) {
  std::string copy(text);  // stb_easy_font takes a mutable char*
  std::vector<OverlayVertex> quads(copy.size() * kBufferBytesPerCharacter / sizeof(OverlayVertex));
  unsigned char rgba[4] = {uint8_t(color & 0xFF), uint8_t(color >> 8 & 0xFF),
                           uint8_t(color >> 16 & 0xFF), uint8_t(color >> 24)};
  int quad_count = stb_easy_font_print(0.0f, 0.0f, copy.data(), rgba, quads.data(),
                                       int(quads.size() * sizeof(OverlayVertex)));
  const Vec3 origin(x, y, 0.0f);
  for (int q = 0; q < quad_count; ++q) {
    const OverlayVertex* corner = &quads[size_t(q) * 4];
    for (int i : {0, 1, 2, 0, 2, 3}) {
      out.push_back({corner[i].position * scale + origin, corner[i].color});
    }
  }
}

std::string wrap_text(std::string_view text, float max_width, float scale) {
  const auto width = [scale](std::string line) { return float(stb_easy_font_width(line.data())) * scale; };
  std::string out;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find('\n', start), text.size());
    std::string line(text.substr(start, end - start));
    while (width(line) > max_width && line.size() > 1) {
      // The longest head that fits, cut after a space when there is one.
      size_t cut = line.size() - 1;
      while (cut > 1 && width(line.substr(0, cut)) > max_width) --cut;
      const size_t space = line.rfind(' ', cut);
      if (space != std::string::npos && space > 0) cut = space + 1;
      std::string head = line.substr(0, cut);
      while (!head.empty() && head.back() == ' ') head.pop_back();
      out += head + '\n';
      line.erase(0, cut);
    }
    out += line;
    if (end == text.size()) break;
    out += '\n';
    start = end + 1;
  }
  return out;
}

Vec2 text_size(std::string_view text, float scale) {
  std::string copy(text);
  return Vec2(float(stb_easy_font_width(copy.data())), float(stb_easy_font_height(copy.data()))) * scale;
}

void append_rectangle(float x, float y, float width, float height, Rgba8 color, std::vector<OverlayVertex>& out) {
  const Vec3 a(x, y, 0), b(x + width, y, 0), c(x + width, y + height, 0), d(x, y + height, 0);
  for (const Vec3& p : {a, b, c, a, c, d}) out.push_back({p, color});
}

}  // namespace cellwalk::render
