// Wavefront OBJ reader: "v x y z [w | r g b]" and "f" with v, v/vt, v//vn or v/vt/vn
// references (negative ones count back from the last vertex). Polygons become triangle fans;
// all o/g groups merge into one object; vn and vt are ignored (normals are recomputed, so
// positions map one to one to vertices) and so are materials, lines, points and curves.
#include <string>

#include "scene/readers.hpp"

namespace cellwalk::detail {

namespace {

struct ObjState {
  Mesh mesh;
  size_t colored = 0;  // vertices that carried "r g b"; colours are kept only if all did
  std::vector<uint32_t> polygon;
};

void read_vertex(TextCursor& in, ObjState& s) {
  double v[6];
  int n = 0;
  for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line()) {
    if (n == 6) in.fail("too many values after 'v'");
    v[n++] = in.to_double(t, "a coordinate");
  }
  if (n < 3) in.fail("'v' needs three coordinates");
  s.mesh.positions.emplace_back(v[0], v[1], v[2]);
  if (n == 6) {
    s.mesh.colors.resize(s.mesh.positions.size());  // keeps indices aligned with positions
    s.mesh.colors.back() = rgba8(color_channel(v[3], 1.0), color_channel(v[4], 1.0),
                                 color_channel(v[5], 1.0));
    ++s.colored;
  }
}

// The position index of one "v/vt/vn" reference, 0-based.
uint32_t vertex_reference(TextCursor& in, std::string_view ref, size_t vertex_count) {
  const int64_t i = in.to_int(ref.substr(0, ref.find('/')), "a vertex index");
  const int64_t n = static_cast<int64_t>(vertex_count);
  const int64_t resolved = i < 0 ? n + i : i - 1;
  if (i == 0 || resolved < 0 || resolved >= n)
    in.fail("face uses vertex " + std::to_string(i) + " but " + std::to_string(n) +
            " vertices are defined so far");
  return static_cast<uint32_t>(resolved);
}

void read_face(TextCursor& in, ObjState& s) {
  s.polygon.clear();
  for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line())
    s.polygon.push_back(vertex_reference(in, t, s.mesh.positions.size()));
  if (s.polygon.size() < 3)
    in.fail("face has " + std::to_string(s.polygon.size()) +
            " vertices; a face needs at least 3");
  append_fan(s.mesh.indices, s.polygon);
}

}  // namespace

Object read_obj(Bytes bytes, const std::string& name) {
  TextCursor in(bytes, name, '#');
  ObjState s;
  for (std::string_view key = in.token(); !key.empty(); key = in.token()) {
    if (key == "v") read_vertex(in, s);
    else if (key == "f") read_face(in, s);
    in.next_line();
  }
  if (s.colored != s.mesh.positions.size()) s.mesh.colors.clear();
  Object object;
  object.mesh = std::move(s.mesh);
  return object;
}

}  // namespace cellwalk::detail
