// Wavefront OBJ reader: "v x y z [w | r g b]", "vt u v" and "f" with v, v/vt, v//vn or v/vt/vn
// references (negative ones count back from the last vertex). Polygons become triangle fans.
// Each o/g group becomes one object (faces of a group named again join it; "o A" then "g b"
// names the group "A/b"), so culling and LOD work on the parts the modeller made. Materials:
// "mtllib" files beside the model are read for "newmtl", "Kd" and "map_Kd"; an object gets its
// first material's Kd as its colour, and per-vertex colours when it uses several. A group whose
// faces show several map_Kd textures becomes one object per texture ("group/material"), since a
// mesh samples one texture. vn is ignored (normals are recomputed), and so are lines, points
// and curves. vt's v runs up the image; cellwalk's uvs run down it (as glTF's), so v is flipped.
#include <algorithm>
#include <array>
#include <cstdio>
#include <optional>
#include <filesystem>
#include <map>
#include <string>

#include "scene/readers.hpp"

namespace cellwalk::detail {

namespace {

constexpr uint32_t kNoMaterial = UINT32_MAX;
constexpr uint32_t kNoUv = UINT32_MAX;

struct Group {
  std::string name;
  std::vector<uint32_t> corners;     // global position indices, three per triangle
  std::vector<uint32_t> uv_corners;  // global vt indices (kNoUv: none), one per corner
  std::vector<uint32_t> materials;   // one per triangle
};

struct Material {
  std::string name;
  Rgba8 color = Object{}.color;
  std::string texture_file;  // map_Kd; empty for none
  bool has_kd = false;       // without Kd, a textured material shows its texture as it is (white)
};

struct ObjState {
  std::vector<Vec3> positions;
  std::vector<Vec2> uvs;
  std::vector<Rgba8> colors;
  size_t colored = 0;  // vertices that carried "r g b"; colours are kept only if all did
  std::vector<uint32_t> polygon, polygon_uvs;
  std::string object_name, group_name;
  std::vector<Group> groups;
  std::map<std::string, size_t> group_of_name;
  size_t current = SIZE_MAX;  // index into groups; SIZE_MAX: none yet
  std::vector<Material> materials;
  std::map<std::string, uint32_t> material_of_name;
  uint32_t material = kNoMaterial;
  // Textures read so far, by map_Kd file (kNoTexture: unreadable), and the model's table.
  std::map<std::string, uint32_t> texture_of_file;
  std::vector<TextureImage> textures;
};

void read_uv(TextCursor& in, ObjState& s) {
  double v[2] = {0.0, 0.0};
  for (double& x : v) {
    const std::string_view t = in.token_in_line();
    if (t.empty()) break;  // "vt u" leaves v at 0
    x = in.to_double(t, "a texture coordinate");
  }
  s.uvs.emplace_back(float(v[0]), float(1.0 - v[1]));
}

// A "v" line's values: the position, and the colour when it has "r g b".
struct ObjVertex {
  Vec3 position;
  std::optional<Rgba8> color;
};

ObjVertex parse_vertex(TextCursor& in) {
  double v[6];
  int n = 0;
  for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line()) {
    if (n == 6) in.fail("too many values after 'v'");
    v[n++] = in.to_double(t, "a coordinate");
  }
  if (n < 3) in.fail("'v' needs three coordinates");
  ObjVertex out{Vec3(v[0], v[1], v[2]), std::nullopt};
  if (n == 6) out.color = rgba8(color_channel(v[3], 1.0), color_channel(v[4], 1.0), color_channel(v[5], 1.0));
  return out;
}

void read_vertex(TextCursor& in, ObjState& s) {
  const ObjVertex v = parse_vertex(in);
  s.positions.push_back(v.position);
  if (v.color) {
    s.colors.resize(s.positions.size());  // keeps indices aligned with positions
    s.colors.back() = *v.color;
    ++s.colored;
  }
}

// A 1-based (or negative, counting back) index among `count` defined so far, 0-based.
uint32_t resolve_reference(TextCursor& in, std::string_view text, size_t count, const char* what,
                           const char* plural) {
  const int64_t i = in.to_int(text, (std::string("a ") + what + " index").c_str());
  const int64_t n = static_cast<int64_t>(count);
  const int64_t resolved = i < 0 ? n + i : i - 1;
  if (i == 0 || resolved < 0 || resolved >= n)
    in.fail("face uses " + std::string(what) + " " + std::to_string(i) + " but " + std::to_string(n) + " " +
            plural + " are defined so far");
  return static_cast<uint32_t>(resolved);
}

// The position and texture coordinate (kNoUv if absent) of one "v/vt/vn" reference, 0-based,
// among the `positions` and `uvs` defined so far.
std::pair<uint32_t, uint32_t> vertex_reference(TextCursor& in, std::string_view ref, size_t positions, size_t uvs) {
  const size_t slash = ref.find('/');
  const uint32_t position = resolve_reference(in, ref.substr(0, slash), positions, "vertex", "vertices");
  if (slash == std::string_view::npos) return {position, kNoUv};
  const std::string_view vt = ref.substr(slash + 1, ref.find('/', slash + 1) - slash - 1);
  return {position, vt.empty() ? kNoUv : resolve_reference(in, vt, uvs, "texture coordinate", "texture coordinates")};
}

// The rest of the line as one name ("g a b" names the group "a b"); `fallback` when empty.
std::string name_in_line(TextCursor& in, const std::string& fallback) {
  std::string name;
  for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line())
    name += (name.empty() ? "" : " ") + std::string(t);
  return name.empty() ? fallback : name;
}

// The group faces go to now, made on first use so that names without faces make no object.
Group& current_group(ObjState& s, const std::string& stem) {
  if (s.current == SIZE_MAX) {
    const std::string name = s.object_name.empty()   ? (s.group_name.empty() ? stem : s.group_name)
                             : s.group_name.empty() ? s.object_name
                                                    : s.object_name + "/" + s.group_name;
    auto [it, added] = s.group_of_name.emplace(name, s.groups.size());
    if (added) s.groups.push_back({name, {}, {}});
    s.current = it->second;
  }
  return s.groups[s.current];
}

void read_face(TextCursor& in, ObjState& s, const std::string& stem) {
  s.polygon.clear();
  s.polygon_uvs.clear();
  for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line()) {
    const auto [position, uv] = vertex_reference(in, t, s.positions.size(), s.uvs.size());
    s.polygon.push_back(position);
    s.polygon_uvs.push_back(uv);
  }
  if (s.polygon.size() < 3)
    in.fail("face has " + std::to_string(s.polygon.size()) + " vertices; a face needs at least 3");
  Group& g = current_group(s, stem);
  append_fan(g.corners, s.polygon);
  append_fan(g.uv_corners, s.polygon_uvs);
  g.materials.resize(g.corners.size() / 3, s.material);
}

// "newmtl NAME" ... "Kd r g b", "map_Kd [options] FILE" of one .mtl file. Errors name the
// .mtl file and its line.
void read_mtl(Bytes bytes, const std::string& name, ObjState& s) {
  TextCursor in(bytes, name, '#');
  uint32_t current = kNoMaterial;
  for (std::string_view key = in.token(); !key.empty(); key = in.token()) {
    if (key == "newmtl") {
      const std::string material = name_in_line(in, "");
      if (material.empty()) in.fail("'newmtl' needs a name");
      auto [it, added] = s.material_of_name.emplace(material, uint32_t(s.materials.size()));
      if (added) s.materials.push_back({material, Object{}.color, ""});
      current = it->second;
    } else if (key == "Kd" && current != kNoMaterial) {
      double c[3];
      for (double& v : c) {
        const std::string_view t = in.token_in_line();
        if (t.empty()) in.fail("'Kd' needs three values");
        v = in.to_double(t, "a colour value");
      }
      s.materials[current].color = rgba8(color_channel(c[0], 1.0), color_channel(c[1], 1.0), color_channel(c[2], 1.0));
      s.materials[current].has_kd = true;
    } else if (key == "map_Kd" && current != kNoMaterial) {
      // Options ("-s 1 1 1", "-clamp on") come first; the file is the last token.
      std::string_view file;
      for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line()) file = t;
      if (file.empty()) in.fail("'map_Kd' needs a file name");
      // Exporters on Windows write ".\\wall.jpg": a backslash is a separator there.
      std::string path(file);
      std::replace(path.begin(), path.end(), '\\', '/');
      s.materials[current].texture_file = path;
      if (!s.materials[current].has_kd) s.materials[current].color = rgba8(255, 255, 255);
    }
    in.next_line();
  }
}

// "mtllib a.mtl b.mtl": each file below `base_dir` that exists is read; a missing one leaves
// its materials uncoloured (many exported models name files they were not shipped with).
void read_mtllib(TextCursor& in, ObjState& s, const std::string& base_dir) {
  for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line()) {
    if (base_dir.empty()) continue;
    const std::filesystem::path file = (std::filesystem::path(base_dir) / std::string(t)).lexically_normal();
    const auto rel = file.lexically_relative(base_dir);
    if (rel.empty() || *rel.begin() == ".." || !std::filesystem::is_regular_file(file)) continue;
    read_mtl(read_whole_file(file.string()), file.string(), s);
  }
}

void use_material(TextCursor& in, ObjState& s) {
  const std::string name = name_in_line(in, "");
  auto it = s.material_of_name.find(name);
  if (it == s.material_of_name.end()) {  // not (yet) defined: a colourless material of its own
    it = s.material_of_name.emplace(name, uint32_t(s.materials.size())).first;
    s.materials.push_back({name, Object{}.color, ""});
  }
  s.material = it->second;
}

// The index of the texture material m shows in the model's table, read on first use;
// kNoTexture for none or one that cannot be read.
uint32_t texture_of(uint32_t m, ObjState& s, const std::string& base_dir, const std::string& model) {
  if (m == kNoMaterial || s.materials[m].texture_file.empty()) return kNoTexture;
  const std::string& file = s.materials[m].texture_file;
  auto [it, added] = s.texture_of_file.emplace(file, kNoTexture);
  if (added) {
    if (std::optional<TextureImage> t = read_texture_file(file, base_dir, model)) {
      it->second = uint32_t(s.textures.size());
      s.textures.push_back(std::move(*t));
    }
  }
  return it->second;
}

// A group's triangles split by the texture their material shows (one part when there is one).
std::vector<std::pair<Group, uint32_t>> parts_by_texture(const Group& g, ObjState& s, const std::string& base_dir,
                                                         const std::string& model) {
  std::map<uint32_t, Group> parts;
  size_t without_vt = 0;
  for (size_t t = 0; t < g.materials.size(); ++t) {
    uint32_t texture = texture_of(g.materials[t], s, base_dir, model);
    const auto corner_uvs = g.uv_corners.begin() + 3 * t;
    if (texture != kNoTexture && std::find(corner_uvs, corner_uvs + 3, kNoUv) != corner_uvs + 3) {
      texture = kNoTexture;  // nothing to say where on the texture the face lies
      ++without_vt;
    }
    Group& part = parts[texture];
    if (part.name.empty()) part.name = g.name;
    part.corners.insert(part.corners.end(), g.corners.begin() + 3 * t, g.corners.begin() + 3 * t + 3);
    part.uv_corners.insert(part.uv_corners.end(), g.uv_corners.begin() + 3 * t, g.uv_corners.begin() + 3 * t + 3);
    part.materials.push_back(g.materials[t]);
  }
  if (without_vt > 0)
    std::fprintf(stderr, "note: %s: group %s: %zu faces of a textured material have no vt; they are drawn untextured\n",
                 model.c_str(), g.name.c_str(), without_vt);
  std::vector<std::pair<Group, uint32_t>> out;
  for (auto& [texture, part] : parts) {
    if (parts.size() > 1 && texture != kNoTexture) part.name += "/" + s.materials[part.materials.front()].name;
    out.emplace_back(std::move(part), texture);
  }
  return out;
}

// The object of a group's part that shows `texture`: its own vertices in the file's order (one
// per position, material when it has several, and texture coordinate when it is textured),
// unfinished. REQUIRES: every corner of a textured part has a vt (parts_by_texture).
Object object_of(const Group& g, const ObjState& s, uint32_t texture) {
  bool several = false;
  for (uint32_t m : g.materials) several |= m != g.materials.front();
  const bool vertex_colors = s.colored == s.positions.size() && s.colored > 0;
  const bool textured = texture != kNoTexture;
  Object object;
  object.name = g.name;
  if (g.materials.front() != kNoMaterial) object.color = s.materials[g.materials.front()].color;
  using Key = std::array<uint32_t, 3>;  // position, material, texture coordinate
  const auto key_of = [&](size_t corner) {
    return Key{g.corners[corner], several ? g.materials[corner / 3] : 0, textured ? g.uv_corners[corner] : 0};
  };
  std::vector<Key> keys(g.corners.size());
  for (size_t c = 0; c < keys.size(); ++c) keys[c] = key_of(c);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  for (const auto& [position, material, uv] : keys) {
    object.mesh.positions.push_back(s.positions[position]);
    if (vertex_colors) object.mesh.colors.push_back(s.colors[position]);
    else if (several) object.mesh.colors.push_back(material == kNoMaterial ? Object{}.color : s.materials[material].color);
    if (textured) object.mesh.uvs.push_back(s.uvs[uv]);
  }
  if (textured) object.mesh.texture = texture;
  object.mesh.indices.reserve(g.corners.size());
  for (size_t c = 0; c < g.corners.size(); ++c)
    object.mesh.indices.push_back(uint32_t(std::lower_bound(keys.begin(), keys.end(), key_of(c)) - keys.begin()));
  return object;
}

}  // namespace

ImportedModel read_obj(Bytes bytes, const std::string& name, const std::string& base_dir) {
  TextCursor in(bytes, name, '#');
  ObjState s;
  const std::string stem = std::filesystem::path(name).stem().string();
  for (std::string_view key = in.token(); !key.empty(); key = in.token()) {
    if (key == "v") {
      read_vertex(in, s);
    } else if (key == "vt") {
      read_uv(in, s);
    } else if (key == "f") {
      read_face(in, s, stem);
    } else if (key == "o") {
      s.object_name = name_in_line(in, stem);
      s.group_name.clear();
      s.current = SIZE_MAX;
    } else if (key == "g") {
      s.group_name = name_in_line(in, "");
      s.current = SIZE_MAX;
    } else if (key == "usemtl") {
      use_material(in, s);
    } else if (key == "mtllib") {
      read_mtllib(in, s, base_dir);
    }
    in.next_line();
  }
  std::vector<Object> objects;
  for (const Group& g : s.groups)
    for (const auto& [part, texture] : parts_by_texture(g, s, base_dir, name)) objects.push_back(object_of(part, s, texture));
  // A point cloud (vertices, no faces) is one object without triangles.
  if (objects.empty() && !s.positions.empty()) {
    objects.emplace_back();
    objects.back().name = stem;
    objects.back().mesh.positions = s.positions;
    if (s.colored == s.positions.size()) objects.back().mesh.colors = s.colors;
  }
  return {std::move(objects), std::move(s.textures)};
}

void read_obj_geometry(Bytes bytes, const std::string& name, MeshBuilder& out) {
  TextCursor in(bytes, name, '#');
  out.begin_vertices(0, false, false);
  uint64_t positions = 0, uvs = 0, lines = 0;
  bool dropped = false;
  std::vector<uint32_t> polygon;
  for (std::string_view key = in.token(); !key.empty(); key = in.token()) {
    if (key == "v") {
      if (positions == UINT32_MAX) in.fail("more than 2^32 - 1 vertices");
      out.vertex(parse_vertex(in).position, Vec3(0.0f), 0);
      ++positions;
    } else if (key == "vt") {
      ++uvs;  // counted, so that face references are checked as read_obj checks them
    } else if (key == "f") {
      polygon.clear();
      for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line())
        polygon.push_back(vertex_reference(in, t, positions, uvs).first);
      if (polygon.size() < 3) in.fail("face has " + std::to_string(polygon.size()) + " vertices; a face needs at least 3");
      out.polygon(polygon);
    } else if (key == "o" || key == "g" || key == "usemtl" || key == "mtllib") {
      dropped = true;
    }
    in.next_line();
    if (++lines % kItemsBetweenReports == 0) out.consumed(in.offset());
  }
  out.consumed(in.offset());
  if (dropped)
    std::fprintf(stderr, "note: %s: read streamed as one mesh cut into patches; its groups and materials are not kept\n",
                 name.c_str());
}

}  // namespace cellwalk::detail
