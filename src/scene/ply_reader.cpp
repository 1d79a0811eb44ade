// PLY reader (Greg Turk's polygon file format): ascii, binary_little_endian and
// binary_big_endian. Reads vertex x y z, optional nx ny nz and red green blue [alpha] (also
// diffuse_*), and the face list vertex_indices / vertex_index with any count and index types;
// every other property and element is read past. Polygons become triangle fans.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <optional>
#include <string>

#include "cellwalk/core/error.hpp"
#include "scene/readers.hpp"

namespace cellwalk::detail {

namespace {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
enum class PlyFormat { kAscii, kLittleEndian, kBigEndian };

struct Property {
  std::string name;
  PlyType type = PlyType::kFloat32;  // of the items, for a list
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
};

struct Header {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<Element> elements;
};

size_t size_of(PlyType t) {
  switch (t) {
    case PlyType::kInt8: case PlyType::kUint8: return 1;
    case PlyType::kInt16: case PlyType::kUint16: return 2;
    case PlyType::kInt32: case PlyType::kUint32: case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 0;
}

bool is_float(PlyType t) { return t == PlyType::kFloat32 || t == PlyType::kFloat64; }

std::optional<PlyType> type_named(std::string_view s) {
  struct Name { std::string_view a, b; PlyType t; };
  static constexpr Name kNames[] = {
      {"char", "int8", PlyType::kInt8},       {"uchar", "uint8", PlyType::kUint8},
      {"short", "int16", PlyType::kInt16},    {"ushort", "uint16", PlyType::kUint16},
      {"int", "int32", PlyType::kInt32},      {"uint", "uint32", PlyType::kUint32},
      {"float", "float32", PlyType::kFloat32}, {"double", "float64", PlyType::kFloat64}};
  for (const Name& n : kNames)
    if (s == n.a || s == n.b) return n.t;
  return std::nullopt;
}

PlyType parse_type(TextCursor& in, std::string_view token) {
  if (auto t = type_named(token)) return *t;
  in.fail("unknown property type '" + std::string(token.substr(0, 40)) + "'");
}

Property parse_property(TextCursor& in) {
  Property p;
  std::string_view t = in.token_in_line();
  if (t == "list") {
    p.is_list = true;
    p.count_type = parse_type(in, in.token_in_line());
    if (is_float(p.count_type)) in.fail("a list count must have an integer type");
    t = in.token_in_line();
  }
  p.type = parse_type(in, t);
  p.name = in.token_in_line();
  if (p.name.empty()) in.fail("property without a name");
  return p;
}

PlyFormat parse_format(TextCursor& in) {
  const std::string_view f = in.token_in_line();
  if (f == "ascii") return PlyFormat::kAscii;
  if (f == "binary_little_endian") return PlyFormat::kLittleEndian;
  if (f == "binary_big_endian") return PlyFormat::kBigEndian;
  in.fail("unknown format '" + std::string(f.substr(0, 40)) + "'");
}

// Leaves `in` at the first byte of the body. Unknown header lines are skipped: some writers
// put free text there (Blender 2.47 did).
Header parse_header(TextCursor& in) {
  if (in.token_in_line() != "ply" || !in.token_in_line().empty())
    in.fail("not a PLY file: the first line must be 'ply'");
  in.next_line();
  Header h;
  bool has_format = false;
  for (;;) {
    if (in.at_end()) in.fail("header has no end_header line");
    const std::string_view key = in.token_in_line();
    if (key == "end_header") {
      in.next_line();
      break;
    }
    if (key == "format") {
      h.format = parse_format(in);
      has_format = true;
    } else if (key == "element") {
      Element e;
      e.name = in.token_in_line();
      // Checked against the body once the header's end is known (read_element).
      e.count = in.to_count(in.token_in_line(), "element count", 0);
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) in.fail("property before any element");
      h.elements.back().properties.push_back(parse_property(in));
    }
    in.next_line();
  }
  if (!has_format) in.fail("header has no format line");
  return h;
}

// Reads body values, ascii or binary, as doubles (exact for every PLY integer type).
class BodyReader {
 public:
  BodyReader(TextCursor& text, Bytes bytes, PlyFormat format, const std::string& name)
      : text_(text), bytes_(bytes), format_(format), name_(name), pos_(text.offset()) {}

  double read(PlyType t) {
    if (format_ == PlyFormat::kAscii) {
      const std::string_view token = text_.token();
      if (token.empty()) fail("file ends inside the body");
      return text_.to_double(token, "a number");
    }
    const size_t n = size_of(t);
    if (bytes_.size() - pos_ < n) fail("file ends inside the body");
    uint8_t raw[8];
    std::memcpy(raw, bytes_.data() + pos_, n);
    if ((format_ == PlyFormat::kBigEndian) != (std::endian::native == std::endian::big))
      std::reverse(raw, raw + n);
    pos_ += n;
    return decode(raw, t);
  }

  // The least bytes `count` records of `e` take; lists are taken as empty.
  void check_fits(const Element& e) const {
    size_t each = 0;
    for (const Property& p : e.properties)
      each += format_ == PlyFormat::kAscii ? 2 : size_of(p.is_list ? p.count_type : p.type);
    if (each > 0 && e.count > remaining() / each)
      fail("element '" + e.name + "' declares " + std::to_string(e.count) +
           " items but only " + std::to_string(remaining()) + " bytes are left");
  }

  // Bytes of the input read so far.
  uint64_t offset() const { return format_ == PlyFormat::kAscii ? text_.offset() : pos_; }

  uint64_t read_list_count(const Property& p) {
    const double n = read(p.count_type);
    const size_t each = format_ == PlyFormat::kAscii ? 2 : size_of(p.type);
    if (!(n >= 0.0 && n <= double(remaining() / each)))
      fail("list '" + p.name + "' has a count of " + std::to_string(n) +
           " that does not fit in the bytes left");
    if (n != std::floor(n))
      fail("list '" + p.name + "' has a count of " + std::to_string(n) +
           ", not a whole number (do the values match the header?)");
    return static_cast<uint64_t>(n);
  }

  [[noreturn]] void fail(std::string_view what) const {
    if (format_ == PlyFormat::kAscii) text_.fail(what);
    cellwalk::fail(name_ + "@" + std::to_string(pos_), what);
  }

 private:
  size_t remaining() const {
    return format_ == PlyFormat::kAscii ? text_.remaining() : bytes_.size() - pos_;
  }

  static double decode(const uint8_t* raw, PlyType t) {
    auto as = [raw]<typename T>(T) {
      T v;
      std::memcpy(&v, raw, sizeof v);
      return static_cast<double>(v);
    };
    switch (t) {
      case PlyType::kInt8: return as(int8_t{});
      case PlyType::kUint8: return as(uint8_t{});
      case PlyType::kInt16: return as(int16_t{});
      case PlyType::kUint16: return as(uint16_t{});
      case PlyType::kInt32: return as(int32_t{});
      case PlyType::kUint32: return as(uint32_t{});
      case PlyType::kFloat32: return as(float{});
      case PlyType::kFloat64: return as(double{});
    }
    return 0.0;
  }

  TextCursor& text_;
  Bytes bytes_;
  PlyFormat format_;
  const std::string& name_;
  size_t pos_;
};

// Which property of the vertex element feeds which attribute (-1: absent).
struct VertexLayout {
  int position[3] = {-1, -1, -1};
  int normal[3] = {-1, -1, -1};
  int color[4] = {-1, -1, -1, -1};
};

VertexLayout vertex_layout(const Element& e, const BodyReader& body) {
  VertexLayout l;
  static constexpr std::string_view kPos[] = {"x", "y", "z"};
  static constexpr std::string_view kNormal[] = {"nx", "ny", "nz"};
  static constexpr std::string_view kColor[] = {"red", "green", "blue", "alpha"};
  for (int i = 0; i < static_cast<int>(e.properties.size()); ++i) {
    const Property& p = e.properties[i];
    if (p.is_list) continue;
    std::string_view n = p.name;
    if (n.starts_with("diffuse_")) n.remove_prefix(8);
    for (int k = 0; k < 3; ++k) {
      if (n == kPos[k]) l.position[k] = i;
      if (n == kNormal[k]) l.normal[k] = i;
    }
    for (int k = 0; k < 4; ++k)
      if (n == kColor[k]) l.color[k] = i;
  }
  for (int k : l.position)
    if (k < 0) body.fail("vertex element lacks one of the properties x, y, z");
  return l;
}

// Float channels are in [0, 1], 16-bit ones in 0..65535, the others in 0..255.
uint8_t to_channel(double v, PlyType t) {
  return color_channel(v, is_float(t) ? 1.0 : size_of(t) == 2 ? 65535.0 : 255.0);
}

void skip_list(BodyReader& body, const Property& p) {
  const uint64_t n = body.read_list_count(p);
  for (uint64_t i = 0; i < n; ++i) body.read(p.type);
}

void read_vertices(BodyReader& body, const Element& e, MeshBuilder& out) {
  const VertexLayout l = vertex_layout(e, body);
  const bool normals = l.normal[0] >= 0 && l.normal[1] >= 0 && l.normal[2] >= 0;
  const bool colors = l.color[0] >= 0 && l.color[1] >= 0 && l.color[2] >= 0;
  out.begin_vertices(e.count, normals, colors);
  std::vector<double> v(e.properties.size(), 0.0);
  for (uint64_t i = 0; i < e.count; ++i) {
    for (size_t k = 0; k < e.properties.size(); ++k) {
      if (e.properties[k].is_list) skip_list(body, e.properties[k]);
      else v[k] = body.read(e.properties[k].type);
    }
    auto vec = [&v](const int (&idx)[3]) { return Vec3(v[idx[0]], v[idx[1]], v[idx[2]]); };
    Rgba8 color = 0;
    if (colors) {
      auto ch = [&](int k) { return to_channel(v[l.color[k]], e.properties[l.color[k]].type); };
      color = rgba8(ch(0), ch(1), ch(2), l.color[3] >= 0 ? ch(3) : 255);
    }
    out.vertex(vec(l.position), normals ? vec(l.normal) : Vec3(0.0f), color);
    if (i % kItemsBetweenReports == 0) out.consumed(body.offset());
  }
}

void read_faces(BodyReader& body, const Element& e, uint64_t vertex_count, MeshBuilder& out) {
  int list = -1;
  for (int i = 0; i < static_cast<int>(e.properties.size()); ++i) {
    const Property& p = e.properties[i];
    if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) list = i;
  }
  if (list < 0) body.fail("face element has no vertex_indices list");
  std::vector<uint32_t> polygon;
  for (uint64_t f = 0; f < e.count; ++f) {
    for (int k = 0; k < static_cast<int>(e.properties.size()); ++k) {
      const Property& p = e.properties[k];
      if (k != list) {
        if (p.is_list) skip_list(body, p);
        else body.read(p.type);
        continue;
      }
      const uint64_t n = body.read_list_count(p);
      if (n < 3) body.fail("face " + std::to_string(f) + " has " + std::to_string(n) +
                           " vertices; a face needs at least 3");
      polygon.clear();
      for (uint64_t i = 0; i < n; ++i) {
        const double index = body.read(p.type);
        if (!(index >= 0.0 && index < double(vertex_count)) || index != double(int64_t(index)))
          body.fail("face " + std::to_string(f) + " uses vertex " + format_number(index) +
                    " but there are " + std::to_string(vertex_count) + " vertices");
        polygon.push_back(static_cast<uint32_t>(index));
      }
      out.polygon(polygon);
    }
    if (f % kItemsBetweenReports == 0) out.consumed(body.offset());
  }
}

void skip_element(BodyReader& body, const Element& e, MeshBuilder& out) {
  if (e.properties.empty()) return;  // nothing to read, however large the count
  for (uint64_t i = 0; i < e.count; ++i) {
    for (const Property& p : e.properties) {
      if (p.is_list) skip_list(body, p);
      else body.read(p.type);
    }
    if (i % kItemsBetweenReports == 0) out.consumed(body.offset());
  }
}


}  // namespace

void read_ply(Bytes bytes, const std::string& name, MeshBuilder& out) {
  TextCursor in(bytes, name, '\0');
  const Header header = parse_header(in);
  BodyReader body(in, bytes, header.format, name);
  uint64_t vertex_count = 0;
  int vertex_elements = 0;
  for (const Element& e : header.elements)
    if (e.name == "vertex") {
      vertex_count = e.count;
      ++vertex_elements;
    }
  if (vertex_elements > 1) in.fail("header declares more than one vertex element");
  if (vertex_count > UINT32_MAX) body.fail("more than 2^32 vertices");

  for (const Element& e : header.elements) {
    body.check_fits(e);
    if (e.name == "vertex") read_vertices(body, e, out);
    else if (e.name == "face") read_faces(body, e, vertex_count, out);
    else skip_element(body, e, out);
  }
  out.consumed(body.offset());
}

}  // namespace cellwalk::detail
