// OFF reader (Geomview Object File Format): "[ST][C][N]OFF", counts "V F E", V vertex lines
// "x y z [nx ny nz] [r g b [a]] [s t]", F face lines "n i0 ... i(n-1) [colour]". Polygons
// become triangle fans; face colours are ignored; 4OFF, nOFF and binary OFF are refused.
#include <array>
#include <string>

#include "scene/readers.hpp"

namespace cellwalk::detail {

namespace {

// The least bytes a vertex ("0 0 0\n") and a face ("3 0 0 0\n") can take: the bound every
// count is checked against before anything is allocated.
constexpr size_t kMinVertexBytes = 6;
constexpr size_t kMinFaceBytes = 8;
constexpr size_t kMaxValuesPerVertex = 12;

struct OffLayout {
  bool texcoords = false;
  bool colors = false;
  bool normals = false;
};

OffLayout parse_keyword(TextCursor& in) {
  std::string_view k = in.token();
  OffLayout layout;
  auto take = [&k](std::string_view prefix) {
    if (!k.starts_with(prefix)) return false;
    k.remove_prefix(prefix.size());
    return true;
  };
  layout.texcoords = take("ST");
  layout.colors = take("C");
  layout.normals = take("N");
  if (k.starts_with("4") || k.starts_with("n"))
    in.fail("4D and n-dimensional OFF are not supported");
  if (k != "OFF") in.fail("not an OFF file: expected a keyword such as OFF, COFF or NOFF");
  return layout;
}

// Colour values are floats in [0, 1] when written with a point or exponent, else 0..255.
uint8_t off_channel(const TextCursor& in, std::string_view token) {
  const bool unit = token.find_first_of(".eE") != std::string_view::npos;
  return color_channel(in.to_double(token, "a colour value"), unit ? 1.0 : 255.0);
}

void read_vertex(TextCursor& in, const OffLayout& layout, MeshBuilder& out) {
  std::array<std::string_view, kMaxValuesPerVertex> v;
  size_t n = 0;
  v[n++] = in.token();
  if (v[0].empty()) in.fail("file ends before all vertices were read");
  for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line()) {
    if (n == v.size()) in.fail("too many values on a vertex line");
    v[n++] = t;
  }
  const size_t needed = 3 + (layout.normals ? 3 : 0) + (layout.texcoords ? 2 : 0);
  if (n < needed || (layout.colors && n != needed + 3 && n != needed + 4) ||
      (!layout.colors && n != needed))
    in.fail("vertex line has " + std::to_string(n) + " values, which does not match the header");
  auto number = [&](size_t i) { return static_cast<float>(in.to_double(v[i], "a coordinate")); };
  Vec3 normal(0.0f);
  Rgba8 color = 0;
  size_t next = 3;
  if (layout.normals) {
    normal = Vec3(number(3), number(4), number(5));
    next = 6;
  }
  if (layout.colors) {
    const bool alpha = n == needed + 4;
    color = rgba8(off_channel(in, v[next]), off_channel(in, v[next + 1]), off_channel(in, v[next + 2]),
                  alpha ? off_channel(in, v[next + 3]) : 255);
  }
  out.vertex(Vec3(number(0), number(1), number(2)), normal, color);
  in.next_line();
}

void read_face(TextCursor& in, uint64_t vertex_count, std::vector<uint32_t>& polygon, MeshBuilder& out) {
  const uint64_t n = in.to_count(in.token(), "face vertex count", 2);
  if (n < 3) in.fail("face has " + std::to_string(n) + " vertices; a face needs at least 3");
  polygon.clear();
  for (uint64_t i = 0; i < n; ++i) {
    const int64_t index = in.to_int(in.token_in_line(), "a vertex index");
    if (index < 0 || static_cast<uint64_t>(index) >= vertex_count)
      in.fail("face uses vertex " + std::to_string(index) + " but there are " +
              std::to_string(vertex_count) + " vertices");
    polygon.push_back(static_cast<uint32_t>(index));
  }
  out.polygon(polygon);
  in.next_line();  // a face colour may follow; it is not used
}

}  // namespace

void read_off(Bytes bytes, const std::string& name, MeshBuilder& out) {
  TextCursor in(bytes, name, '#');
  const OffLayout layout = parse_keyword(in);
  const std::string_view first = in.token();
  if (first == "BINARY") in.fail("binary OFF is not supported");
  const uint64_t vertices = in.to_count(first, "vertex count", kMinVertexBytes);
  const uint64_t faces = in.to_count(in.token_in_line(), "face count", kMinFaceBytes);
  // The edge count is unused, and some writers leave it out.
  if (std::string_view edges = in.token_in_line(); !edges.empty()) in.to_count(edges, "edge count", 0);
  if (vertices > UINT32_MAX) in.fail("more than 2^32 vertices");
  in.next_line();

  out.begin_vertices(vertices, layout.normals, layout.colors);
  for (uint64_t i = 0; i < vertices; ++i) {
    read_vertex(in, layout, out);
    if (i % kItemsBetweenReports == 0) out.consumed(in.offset());
  }
  std::vector<uint32_t> polygon;
  for (uint64_t i = 0; i < faces; ++i) {
    if (in.at_end()) in.fail("file ends after " + std::to_string(i) + " of " +
                             std::to_string(faces) + " faces");
    read_face(in, vertices, polygon, out);
    if (i % kItemsBetweenReports == 0) out.consumed(in.offset());
  }
  out.consumed(in.offset());
}

}  // namespace cellwalk::detail
