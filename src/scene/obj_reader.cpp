// Wavefront OBJ reader: "v x y z [w | r g b]" and "f" with v, v/vt, v//vn or v/vt/vn
// references (negative ones count back from the last vertex). Polygons become triangle fans.
// Each o/g group becomes one object (faces of a group named again join it; "o A" then "g b"
// names the group "A/b"), so culling and LOD work on the parts the modeller made. Materials:
// "mtllib" files beside the model are read for "newmtl" and "Kd"; an object gets its first
// material's Kd as its colour, and per-vertex colours when it uses several. vn and vt are
// ignored (normals are recomputed), and so are lines, points and curves.
#include <algorithm>
#include <filesystem>
#include <map>
#include <string>

#include "scene/readers.hpp"

namespace cellwalk::detail {

namespace {

constexpr uint32_t kNoMaterial = UINT32_MAX;

struct Group {
  std::string name;
  std::vector<uint32_t> corners;    // global position indices, three per triangle
  std::vector<uint32_t> materials;  // one per triangle
};

struct ObjState {
  std::vector<Vec3> positions;
  std::vector<Rgba8> colors;
  size_t colored = 0;  // vertices that carried "r g b"; colours are kept only if all did
  std::vector<uint32_t> polygon;
  std::string object_name, group_name;
  std::vector<Group> groups;
  std::map<std::string, size_t> group_of_name;
  size_t current = SIZE_MAX;  // index into groups; SIZE_MAX: none yet
  std::vector<Rgba8> material_colors;
  std::map<std::string, uint32_t> material_of_name;
  uint32_t material = kNoMaterial;
};

void read_vertex(TextCursor& in, ObjState& s) {
  double v[6];
  int n = 0;
  for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line()) {
    if (n == 6) in.fail("too many values after 'v'");
    v[n++] = in.to_double(t, "a coordinate");
  }
  if (n < 3) in.fail("'v' needs three coordinates");
  s.positions.emplace_back(v[0], v[1], v[2]);
  if (n == 6) {
    s.colors.resize(s.positions.size());  // keeps indices aligned with positions
    s.colors.back() = rgba8(color_channel(v[3], 1.0), color_channel(v[4], 1.0), color_channel(v[5], 1.0));
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
  for (std::string_view t = in.token_in_line(); !t.empty(); t = in.token_in_line())
    s.polygon.push_back(vertex_reference(in, t, s.positions.size()));
  if (s.polygon.size() < 3)
    in.fail("face has " + std::to_string(s.polygon.size()) + " vertices; a face needs at least 3");
  Group& g = current_group(s, stem);
  append_fan(g.corners, s.polygon);
  g.materials.resize(g.corners.size() / 3, s.material);
}

// "newmtl NAME" ... "Kd r g b" of one .mtl file. Errors name the .mtl file and its line.
void read_mtl(Bytes bytes, const std::string& name, ObjState& s) {
  TextCursor in(bytes, name, '#');
  uint32_t current = kNoMaterial;
  for (std::string_view key = in.token(); !key.empty(); key = in.token()) {
    if (key == "newmtl") {
      const std::string material = name_in_line(in, "");
      if (material.empty()) in.fail("'newmtl' needs a name");
      auto [it, added] = s.material_of_name.emplace(material, uint32_t(s.material_colors.size()));
      if (added) s.material_colors.push_back(Object{}.color);
      current = it->second;
    } else if (key == "Kd" && current != kNoMaterial) {
      double c[3];
      for (double& v : c) {
        const std::string_view t = in.token_in_line();
        if (t.empty()) in.fail("'Kd' needs three values");
        v = in.to_double(t, "a colour value");
      }
      s.material_colors[current] = rgba8(color_channel(c[0], 1.0), color_channel(c[1], 1.0), color_channel(c[2], 1.0));
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
    it = s.material_of_name.emplace(name, uint32_t(s.material_colors.size())).first;
    s.material_colors.push_back(Object{}.color);
  }
  s.material = it->second;
}

// The group's object: its own vertices in the file's order (one per position and material
// when it has several materials, so that each carries its colour), unfinished.
Object object_of(const Group& g, const ObjState& s) {
  bool several = false;
  for (uint32_t m : g.materials) several |= m != g.materials.front();
  const bool vertex_colors = s.colored == s.positions.size() && s.colored > 0;
  Object object;
  object.name = g.name;
  if (g.materials.front() != kNoMaterial) object.color = s.material_colors[g.materials.front()];
  const auto key_of = [&](size_t corner) {
    return uint64_t(g.corners[corner]) << 32 | (several ? g.materials[corner / 3] : 0);
  };
  std::vector<uint64_t> keys(g.corners.size());
  for (size_t c = 0; c < keys.size(); ++c) keys[c] = key_of(c);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  for (uint64_t key : keys) {
    const uint32_t position = uint32_t(key >> 32), material = uint32_t(key);
    object.mesh.positions.push_back(s.positions[position]);
    if (vertex_colors) object.mesh.colors.push_back(s.colors[position]);
    else if (several) object.mesh.colors.push_back(material == kNoMaterial ? Object{}.color : s.material_colors[material]);
  }
  object.mesh.indices.reserve(g.corners.size());
  for (size_t c = 0; c < g.corners.size(); ++c)
    object.mesh.indices.push_back(uint32_t(std::lower_bound(keys.begin(), keys.end(), key_of(c)) - keys.begin()));
  return object;
}

}  // namespace

std::vector<Object> read_obj(Bytes bytes, const std::string& name, const std::string& base_dir) {
  TextCursor in(bytes, name, '#');
  ObjState s;
  const std::string stem = std::filesystem::path(name).stem().string();
  for (std::string_view key = in.token(); !key.empty(); key = in.token()) {
    if (key == "v") {
      read_vertex(in, s);
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
  for (const Group& g : s.groups) objects.push_back(object_of(g, s));
  // A point cloud (vertices, no faces) is one object without triangles.
  if (objects.empty() && !s.positions.empty()) {
    objects.emplace_back();
    objects.back().name = stem;
    objects.back().mesh.positions = s.positions;
    if (s.colored == s.positions.size()) objects.back().mesh.colors = s.colors;
  }
  return objects;
}

}  // namespace cellwalk::detail
