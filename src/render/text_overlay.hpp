// Text for overlays (frame statistics, labels) as plain triangles: stb_easy_font builds glyphs
// from quads, so no font texture is needed and the overlay shares the line program.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "cellwalk/scene/mesh.hpp"

namespace cellwalk::render {

// The overlay vertex: position and colour, the same 16-byte layout stb_easy_font writes.
struct OverlayVertex {
  Vec3 position{0.0f};
  Rgba8 color = 0;
};
static_assert(sizeof(OverlayVertex) == 16);

// Appends the triangles of `text` (six vertices per glyph quad) in pixel coordinates, y down,
// with the text's top-left corner at (x, y) and glyphs `scale` times their 8-pixel height.
// Characters outside printable ASCII draw nothing.
void append_text(float x, float y, std::string_view text, Rgba8 color, float scale,
                 std::vector<OverlayVertex>& out);

// `text` with its lines broken at spaces (or, for a word too long, anywhere) so that none is
// wider than `max_width` pixels at `scale`.
std::string wrap_text(std::string_view text, float max_width, float scale);

// The size in pixels (width, height) of `text` drawn at `scale`.
Vec2 text_size(std::string_view text, float scale);

// Appends two triangles covering the rectangle from (x, y) to (x + width, y + height).
void append_rectangle(float x, float y, float width, float height, Rgba8 color, std::vector<OverlayVertex>& out);

}  // namespace cellwalk::render
