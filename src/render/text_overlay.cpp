// Text overlay through stb_easy_font (Sean Barrett, public domain): quads to triangles.
#include "render/text_overlay.hpp"

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

}  // namespace cellwalk::render
