// glTF 2.0 / GLB reader on tinygltf (syoyo/tinygltf): one object per triangle primitive of each
// mesh node of the default scene, with the node hierarchy's transforms applied and the
// primitive's material's base colour and base-colour texture (baseColorTexture with its
// TEXCOORD_n; the sampler's wrap modes and KHR_texture_transform are not read: textures
// repeat). tinygltf parses the JSON and resolves
// buffers; everything it does not check is checked here: the GLB framing, that accessors lie
// inside their buffer views and views inside their buffers, index ranges, node cycles.
// Triangle primitives (lists, strips, fans) are read; points and lines are skipped.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <optional>
#include <filesystem>
#include <string_view>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "cellwalk/core/error.hpp"
#include "scene/readers.hpp"

namespace cellwalk::detail {

namespace {

// --- loading -------------------------------------------------------------------------------

uint32_t le32(Bytes b, size_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// tinygltf trusts the GLB chunk lengths more than it should; check the framing first so a bad
// file gets an error with its byte offset.
void check_glb_framing(Bytes b, const std::string& name) {
  auto fail_at = [&name](size_t at, const std::string& what) {
    fail(name + "@" + std::to_string(at), what);
  };
  if (b.size() < 20) fail_at(0, "GLB file shorter than its 20-byte header");
  if (le32(b, 4) != 2) fail_at(4, "GLB version " + std::to_string(le32(b, 4)) + " is not 2");
  const uint64_t total = le32(b, 8);
  if (total > b.size() || total < 20)
    fail_at(8, "GLB length " + std::to_string(total) + " does not match the file size " +
                   std::to_string(b.size()));
  for (uint64_t at = 12, chunk = 0; at < total; ++chunk) {
    if (total - at < 8) fail_at(at, "GLB chunk header runs past the end");
    const uint64_t length = le32(b, at);
    const uint32_t type = le32(b, at + 4);
    if (length > total - at - 8)
      fail_at(at, "GLB chunk length " + std::to_string(length) + " runs past the end");
    if (chunk == 0 && type != 0x4E4F534Au) fail_at(at + 4, "first GLB chunk is not JSON");
    at += 8 + length;
  }
}

// tinygltf's JSON parser recurses once per array or object level, so a small file of deeply
// nested brackets overflows the stack; a linear pre-scan bounds the depth before it parses.
constexpr int kMaxJsonDepth = 64;

void check_json_depth(std::string_view json, size_t offset, const std::string& name) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth)
        fail(name + "@" + std::to_string(offset + i), "JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                                                          " arrays and objects, which no glTF needs; re-export the model or remove the deep extras");
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

// The JSON of a .gltf (the whole file) or of a GLB (its first chunk, framing already checked).
void check_json_depth_of(Bytes b, bool glb, const std::string& name) {
  const auto* text = reinterpret_cast<const char*>(b.data());
  if (!glb) return check_json_depth(std::string_view(text, b.size()), 0, name);
  if (b.size() >= 20) check_json_depth(std::string_view(text + 20, std::min<size_t>(le32(b, 12), b.size() - 20)), 20, name);
}

// The extensions this reader decodes; a file that requires any other fails naming it, before
// tinygltf would report a symptom ("Invalid byteLength", "invalid bufferView").
constexpr std::string_view kReadableExtensions[] = {"KHR_mesh_quantization", "KHR_materials_unlit",
                                                    "KHR_texture_transform", "EXT_meshopt_compression",
                                                    "KHR_meshopt_compression", "KHR_draco_mesh_compression"};

// Fails when the JSON lists a required extension this reader cannot decode. JSON that does
// not parse is left for tinygltf to report.
void check_required_extensions(Bytes b, bool glb, const std::string& name) {
  const auto* text = reinterpret_cast<const char*>(b.data());
  std::string_view json(text, b.size());
  if (glb) json = b.size() >= 20 ? std::string_view(text + 20, std::min<size_t>(le32(b, 12), b.size() - 20)) : "";
  const nlohmann::json doc = nlohmann::json::parse(json.begin(), json.end(), nullptr, false);
  if (!doc.is_object() || !doc.contains("extensionsRequired") || !doc["extensionsRequired"].is_array()) return;
  for (const nlohmann::json& e : doc["extensionsRequired"]) {
    if (!e.is_string()) continue;
    const std::string ext = e.get<std::string>();
    if (std::find(std::begin(kReadableExtensions), std::end(kReadableExtensions), ext) == std::end(kReadableExtensions))
      fail(name, "requires the glTF extension " + ext + ", which cellwalk cannot read yet; re-export the model without it");
  }
}

// Buffers are read from files only below `base_dir`, and only when it is set.
struct FileAccess {
  std::filesystem::path base_dir;
  bool allows(const std::string& path) const {
    if (base_dir.empty()) return false;
    const auto rel = std::filesystem::path(path).lexically_normal().lexically_relative(base_dir);
    return !rel.empty() && *rel.begin() != "..";
  }
};

tinygltf::FsCallbacks file_callbacks(FileAccess& access) {
  tinygltf::FsCallbacks fs;
  fs.FileExists = [](const std::string& path, void* user) {
    return static_cast<FileAccess*>(user)->allows(path) && std::filesystem::is_regular_file(path);
  };
  fs.ExpandFilePath = [](const std::string& path, void*) { return path; };
  fs.ReadWholeFile = [](std::vector<unsigned char>* out, std::string* err,
                        const std::string& path, void* user) {
    if (!static_cast<FileAccess*>(user)->allows(path)) return false;
    try {
      *out = read_whole_file(path);
      return true;
    } catch (const Error& e) {
      *err += e.what();
      return false;
    }
  };
  fs.WriteWholeFile = [](std::string*, const std::string&, const std::vector<unsigned char>&,
                         void*) { return false; };
  fs.user_data = &access;
  return fs;
}

// Images are kept as their file's bytes (PNG, JPEG), not decoded: scenes store textures
// compressed (scene/texture.hpp). tinygltf hands over a data URI's bytes here; a buffer view's
// are read later, by image_bytes, after its bounds are checked (tinygltf does not check them
// before calling this).
bool keep_image_bytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  if (image->bufferView < 0 && size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

// The bytes of buffer view `index`, or nullopt when it does not lie inside its buffer.
std::optional<std::span<const uint8_t>> view_bytes(const tinygltf::Model& m, int index) {
  if (index < 0 || size_t(index) >= m.bufferViews.size()) return std::nullopt;
  const tinygltf::BufferView& bv = m.bufferViews[index];
  if (bv.buffer < 0 || size_t(bv.buffer) >= m.buffers.size()) return std::nullopt;
  const std::vector<unsigned char>& data = m.buffers[bv.buffer].data;
  if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset || bv.byteLength == 0) return std::nullopt;
  return std::span<const uint8_t>(data.data() + bv.byteOffset, bv.byteLength);
}

std::string first_line(std::string s) {
  s = s.substr(0, s.find('\n'));
  return s.empty() ? "tinygltf could not parse the file" : s;
}

tinygltf::Model load(Bytes bytes, const std::string& name, const std::string& base_dir) {
  bool glb = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
  if (glb) check_glb_framing(bytes, name);
  if (bytes.size() > UINT32_MAX) fail(name, "file larger than 4 GiB");
  check_json_depth_of(bytes, glb, name);
  // Compressed views, then compressed primitives (their streams may lie in compressed views),
  // are decoded first; the rest reads the equivalent uncompressed GLB.
  std::vector<uint8_t> decoded;
  for (auto decode : {decode_meshopt_compression, decode_draco_compression}) {
    try {
      if (std::vector<uint8_t> d = decode(bytes, glb, name, base_dir); !d.empty()) {
        decoded = std::move(d);
        bytes = decoded;
        glb = true;
      }
    } catch (const nlohmann::json::exception& e) {  // a value of the wrong JSON type
      fail(name, std::string("a compressed view or primitive has a field of the wrong type (") + e.what() +
                     "); the file does not follow the glTF schema: re-export it");
    }
  }
  check_required_extensions(bytes, glb, name);
  FileAccess access{base_dir.empty() ? std::filesystem::path()
                                     : std::filesystem::path(base_dir).lexically_normal()};
  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks(file_callbacks(access));
  loader.SetImageLoader(keep_image_bytes, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  try {
    const auto size = static_cast<unsigned int>(bytes.size());
    ok = glb ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), size, base_dir)
             : loader.LoadASCIIFromString(&model, &err, &warn,
                                          reinterpret_cast<const char*>(bytes.data()), size,
                                          base_dir);
  } catch (const std::exception& e) {  // tinygltf is third-party: keep its failures ours
    fail(name, std::string("glTF parser failed: ") + e.what());
  }
  if (!ok) fail(name, first_line(err));
  if (!model.asset.version.starts_with("2."))
    fail(name, "glTF version '" + model.asset.version + "' is not supported; only 2.x is");
  return model;
}

// --- accessors ------------------------------------------------------------------------------

// A checked view of an accessor: element i, component c is at data + i * stride + c * size.
struct AccessorView {
  const uint8_t* data = nullptr;
  size_t stride = 0;
  size_t count = 0;
  int components = 0;
  int component_type = 0;
  bool normalized = false;

  double get(size_t i, int c) const {
    const uint8_t* p = data + i * stride + c * tinygltf::GetComponentSizeInBytes(component_type);
    auto as = [p]<typename T>(T) {
      T v;
      std::memcpy(&v, p, sizeof v);
      return v;
    };
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: return scale(as(int8_t{}), 127.0);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return scale(as(uint8_t{}), 255.0);
      case TINYGLTF_COMPONENT_TYPE_SHORT: return scale(as(int16_t{}), 32767.0);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return scale(as(uint16_t{}), 65535.0);
      case TINYGLTF_COMPONENT_TYPE_INT: return as(int32_t{});
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return as(uint32_t{});
      case TINYGLTF_COMPONENT_TYPE_FLOAT: return as(float{});
      case TINYGLTF_COMPONENT_TYPE_DOUBLE: return as(double{});
    }
    return 0.0;
  }
  Vec3 vec3(size_t i) const { return Vec3(get(i, 0), get(i, 1), get(i, 2)); }

 private:
  // Normalized integers map to [0, 1] or [-1, 1] (glTF 2.0 section 3.11).
  double scale(double v, double max) const {
    return normalized ? std::max(v / max, -1.0) : v;
  }
};

AccessorView view_of(const tinygltf::Model& m, int index, const std::string& where) {
  auto bad = [&where, index](const std::string& what) {
    fail(where, "accessor " + format_number(index) + " " + what);
  };
  if (index < 0 || static_cast<size_t>(index) >= m.accessors.size()) bad("does not exist");
  const tinygltf::Accessor& a = m.accessors[index];
  if (a.sparse.isSparse) bad("is sparse, which is not supported");
  AccessorView v;
  v.count = a.count;
  v.components = tinygltf::GetNumComponentsInType(a.type);
  v.component_type = a.componentType;
  v.normalized = a.normalized;
  const int size = tinygltf::GetComponentSizeInBytes(a.componentType);
  if (v.components <= 0 || v.components > 4 || size <= 0) bad("has an unusable type");
  // Without a view an accessor is all zeros, useful only with sparse data, and its count
  // would be bounded by nothing in the file.
  if (a.bufferView < 0) bad("has no buffer view, which is not supported");
  if (static_cast<size_t>(a.bufferView) >= m.bufferViews.size()) bad("names a missing view");
  const tinygltf::BufferView& bv = m.bufferViews[a.bufferView];
  if (bv.buffer < 0 || static_cast<size_t>(bv.buffer) >= m.buffers.size())
    bad("uses a view of a missing buffer");
  const size_t buffer_size = m.buffers[bv.buffer].data.size();
  if (bv.byteOffset > buffer_size || bv.byteLength > buffer_size - bv.byteOffset)
    bad("uses a view that runs past the end of its buffer");
  const size_t element = static_cast<size_t>(v.components) * size;
  v.stride = bv.byteStride ? bv.byteStride : element;
  if (v.stride < element) bad("has a stride shorter than its element");
  if (a.count > 0 && (a.byteOffset > bv.byteLength || bv.byteLength - a.byteOffset < element ||
                      (a.count - 1) > (bv.byteLength - a.byteOffset - element) / v.stride))
    bad("runs past the end of its buffer view");
  v.data = m.buffers[bv.buffer].data.data() + bv.byteOffset + a.byteOffset;
  return v;
}

// --- primitives and nodes ------------------------------------------------------------------

// Triangle-list indices for `n` vertices of a list, strip or fan (glTF 2.0 section 3.7.2.1).
std::vector<uint32_t> triangles(int mode, const std::vector<uint32_t>& v) {
  if (mode == TINYGLTF_MODE_TRIANGLES) return {v.begin(), v.end() - v.size() % 3};
  std::vector<uint32_t> out;
  for (size_t i = 2; i < v.size(); ++i) {
    if (mode == TINYGLTF_MODE_TRIANGLE_FAN) out.insert(out.end(), {v[0], v[i - 1], v[i]});
    else if (i % 2 == 0) out.insert(out.end(), {v[i - 2], v[i - 1], v[i]});
    else out.insert(out.end(), {v[i - 1], v[i - 2], v[i]});  // keeps strip winding
  }
  return out;
}

bool is_triangles(int mode) {
  return mode == -1 || mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP ||
         mode == TINYGLTF_MODE_TRIANGLE_FAN;
}

int attribute(const tinygltf::Primitive& p, const char* name) {
  auto it = p.attributes.find(name);
  return it == p.attributes.end() ? -1 : it->second;
}

// TEXCOORD_<set> as uvs (floats, or normalised bytes/shorts as KHR_mesh_quantization allows).
void read_uvs(const tinygltf::Model& m, const tinygltf::Primitive& p, int set, size_t vertex_count,
              const std::string& where, Mesh& mesh) {
  const std::string name = "TEXCOORD_" + std::to_string(set);
  const int index = attribute(p, name.c_str());
  if (index < 0) return;
  const AccessorView uv = view_of(m, index, where);
  if (uv.components != 2 || uv.count != vertex_count) fail(where, name + " does not match POSITION");
  mesh.uvs.resize(uv.count);
  for (size_t i = 0; i < uv.count; ++i) mesh.uvs[i] = Vec2(float(uv.get(i, 0)), float(uv.get(i, 1)));
}

Mesh read_primitive(const tinygltf::Model& m, const tinygltf::Primitive& p,
                    const std::string& where) {
  Mesh mesh;
  const AccessorView pos = view_of(m, attribute(p, "POSITION"), where);
  if (pos.components != 3) fail(where, "POSITION is not a VEC3");
  if (pos.count > UINT32_MAX) fail(where, "more than 2^32 vertices");
  mesh.positions.resize(pos.count);
  for (size_t i = 0; i < pos.count; ++i) mesh.positions[i] = pos.vec3(i);
  if (int n = attribute(p, "NORMAL"); n >= 0) {
    const AccessorView nv = view_of(m, n, where);
    if (nv.components != 3 || nv.count != pos.count) fail(where, "NORMAL does not match POSITION");
    mesh.normals.resize(nv.count);
    for (size_t i = 0; i < nv.count; ++i) mesh.normals[i] = nv.vec3(i);
  }
  if (int c = attribute(p, "COLOR_0"); c >= 0) {
    const AccessorView cv = view_of(m, c, where);
    if (cv.components < 3 || cv.count != pos.count) fail(where, "COLOR_0 does not match POSITION");
    auto ch = [&cv](size_t i, int k) {
      return color_channel(k < cv.components ? cv.get(i, k) : 1.0, 1.0);
    };
    mesh.colors.resize(cv.count);
    for (size_t i = 0; i < cv.count; ++i) mesh.colors[i] = rgba8(ch(i, 0), ch(i, 1), ch(i, 2), ch(i, 3));
  }
  std::vector<uint32_t> order;
  if (p.indices >= 0) {
    const AccessorView iv = view_of(m, p.indices, where);
    if (iv.components != 1 || iv.normalized) fail(where, "indices are not plain scalars");
    // glTF 2.0 section 3.7.2.1: indices are unsigned integers. A float index (1.7) has no
    // vertex to name; truncating it would silently draw another triangle.
    if (iv.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        iv.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        iv.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      fail(where, "index accessor " + std::to_string(p.indices) + " has component type " +
                      std::to_string(iv.component_type) +
                      "; glTF indices must be unsigned bytes, shorts or ints (5121, 5123, 5125): re-export the model");
    order.resize(iv.count);
    for (size_t i = 0; i < iv.count; ++i) {
      const double index = iv.get(i, 0);
      if (!(index >= 0.0 && index < double(pos.count)))
        fail(where, "index " + format_number(index) + " is out of range for " +
                        std::to_string(pos.count) + " vertices");
      order[i] = static_cast<uint32_t>(index);
    }
  } else {
    order.resize(pos.count);
    for (size_t i = 0; i < pos.count; ++i) order[i] = static_cast<uint32_t>(i);
  }
  mesh.indices = triangles(p.mode == -1 ? TINYGLTF_MODE_TRIANGLES : p.mode, order);
  return mesh;
}

// The model's base-colour textures: the images some material's baseColorTexture shows, each
// once, numbered in the order materials name them.
struct TextureTable {
  std::vector<uint32_t> of_material;  // texture per material, kNoTexture for none
  std::vector<int> texcoord_of_material;
  std::vector<TextureImage> textures;
};

// The encoded bytes of image `i`: held by tinygltf (a buffer view or data URI) or a file
// beside the model; nullopt (with a note) when they cannot be had.
std::optional<TextureImage> image_bytes(const tinygltf::Model& m, int i, const std::string& name,
                                        const std::string& base_dir) {
  const tinygltf::Image& image = m.images[i];
  const std::string label = !image.name.empty() ? image.name : !image.uri.empty() ? image.uri : "image " + std::to_string(i);
  std::span<const uint8_t> bytes = image.image;
  if (image.bufferView >= 0) {
    const std::optional<std::span<const uint8_t>> view = view_bytes(m, image.bufferView);
    if (!view) {
      std::fprintf(stderr, "note: %s: %s lies outside its buffer; its meshes are drawn untextured\n", name.c_str(), label.c_str());
      return std::nullopt;
    }
    bytes = *view;
  } else if (bytes.empty()) {
    if (image.uri.empty() || image.uri.starts_with("data:")) return std::nullopt;
    return read_texture_file(image.uri, base_dir, name);
  }
  return checked_texture({label, {bytes.begin(), bytes.end()}}, name + ": " + label);
}

TextureTable texture_table(const tinygltf::Model& m, const std::string& name, const std::string& base_dir) {
  TextureTable table;
  table.of_material.assign(m.materials.size(), kNoTexture);
  table.texcoord_of_material.assign(m.materials.size(), 0);
  std::map<int, uint32_t> texture_of_image;
  for (size_t k = 0; k < m.materials.size(); ++k) {
    const tinygltf::TextureInfo& info = m.materials[k].pbrMetallicRoughness.baseColorTexture;
    if (info.index < 0 || size_t(info.index) >= m.textures.size()) continue;
    const int image = m.textures[info.index].source;
    if (image < 0 || size_t(image) >= m.images.size()) continue;
    auto [it, added] = texture_of_image.emplace(image, kNoTexture);
    if (added) {
      if (std::optional<TextureImage> t = image_bytes(m, image, name, base_dir)) {
        it->second = uint32_t(table.textures.size());
        table.textures.push_back(std::move(*t));
      }
    }
    table.of_material[k] = it->second;
    table.texcoord_of_material[k] = info.texCoord;
  }
  return table;
}

// The primitive's material's base colour factor; the default colour without one.
Rgba8 material_color(const tinygltf::Model& m, const tinygltf::Primitive& p) {
  if (p.material < 0 || static_cast<size_t>(p.material) >= m.materials.size()) return Object{}.color;
  const std::vector<double>& f = m.materials[p.material].pbrMetallicRoughness.baseColorFactor;
  if (f.size() != 4) return Object{}.color;
  auto ch = [&f](int k) { return color_channel(f[k], 1.0); };
  return rgba8(ch(0), ch(1), ch(2), ch(3));
}

Mat4 local_matrix(const tinygltf::Node& n, const std::string& where) {
  if (n.matrix.size() == 16) {
    Mat4 m;
    for (int i = 0; i < 16; ++i) glm::value_ptr(m)[i] = static_cast<float>(n.matrix[i]);
    return m;
  }
  if (!n.matrix.empty() || (!n.translation.empty() && n.translation.size() != 3) ||
      (!n.rotation.empty() && n.rotation.size() != 4) || (!n.scale.empty() && n.scale.size() != 3))
    fail(where, "malformed transform");
  Mat4 m(1.0f);
  if (!n.translation.empty())
    m = glm::translate(m, Vec3(n.translation[0], n.translation[1], n.translation[2]));
  if (!n.rotation.empty())  // glTF stores x y z w; glm's constructor takes w first
    m *= glm::mat4_cast(glm::quat(float(n.rotation[3]), float(n.rotation[0]),
                                  float(n.rotation[1]), float(n.rotation[2])));
  if (!n.scale.empty()) m = glm::scale(m, Vec3(n.scale[0], n.scale[1], n.scale[2]));
  return m;
}

// A mirroring transform turns counter-clockwise triangles clockwise; swap two corners back.
void keep_winding(Mesh& mesh, const Mat4& m) {
  if (glm::determinant(glm::mat3(m)) >= 0.0f) return;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
}

std::string stem_of(const std::string& name) { return std::filesystem::path(name).stem().string(); }

// One object per triangle primitive of the node's mesh (each primitive has its own material,
// and objects are what culling and LOD work on), unfinished, transformed to world space.
std::vector<Object> objects_of_node(const tinygltf::Model& m, int node_index, const Mat4& world,
                                    const std::string& name, const TextureTable& textures) {
  const tinygltf::Node& node = m.nodes[node_index];
  const std::string where = name + ": node " + std::to_string(node_index);
  if (static_cast<size_t>(node.mesh) >= m.meshes.size()) fail(where, "names a missing mesh");
  const tinygltf::Mesh& gm = m.meshes[node.mesh];
  const std::string base = !node.name.empty() ? node.name
                           : !gm.name.empty() ? gm.name
                                              : stem_of(name) + "#" + std::to_string(node_index);
  size_t triangle_primitives = 0;
  for (const tinygltf::Primitive& p : gm.primitives) triangle_primitives += is_triangles(p.mode);
  std::vector<Object> objects;
  for (size_t k = 0; k < gm.primitives.size(); ++k) {
    if (!is_triangles(gm.primitives[k].mode)) continue;
    Object object;
    object.name = triangle_primitives > 1 ? base + "/" + std::to_string(k) : base;
    object.color = material_color(m, gm.primitives[k]);
    const tinygltf::Primitive& p = gm.primitives[k];
    const std::string at = where + " mesh " + std::to_string(node.mesh) + " primitive " + std::to_string(k);
    object.mesh = read_primitive(m, p, at);
    if (p.material >= 0 && size_t(p.material) < m.materials.size() && textures.of_material[p.material] != kNoTexture) {
      read_uvs(m, p, textures.texcoord_of_material[p.material], object.mesh.vertex_count(), at, object.mesh);
      if (!object.mesh.uvs.empty()) object.mesh.texture = textures.of_material[p.material];
    }
    transform(object.mesh, world);
    keep_winding(object.mesh, world);
    objects.push_back(std::move(object));
  }
  return objects;
}

// The roots to walk: the default scene's (else the first scene's), else every node that is
// no other node's child.
std::vector<int> root_nodes(const tinygltf::Model& m) {
  if (!m.scenes.empty()) {
    const bool valid = m.defaultScene >= 0 && static_cast<size_t>(m.defaultScene) < m.scenes.size();
    return m.scenes[valid ? m.defaultScene : 0].nodes;
  }
  std::vector<bool> child(m.nodes.size(), false);
  for (const tinygltf::Node& n : m.nodes)
    for (int c : n.children)
      if (c >= 0 && static_cast<size_t>(c) < child.size()) child[c] = true;
  std::vector<int> roots;
  for (size_t i = 0; i < child.size(); ++i)
    if (!child[i]) roots.push_back(static_cast<int>(i));
  return roots;
}

}  // namespace

ImportedModel read_gltf(Bytes bytes, const std::string& name, ObjectId first_id,
                        const std::string& base_dir) {
  const tinygltf::Model m = load(bytes, name, base_dir);
  TextureTable table = texture_table(m, name, base_dir);
  std::vector<Object> objects;
  // Depth-first with an explicit stack: a deep or cyclic node graph must neither overflow the
  // call stack nor loop; each node is visited once (glTF nodes form disjoint trees).
  std::vector<bool> visited(m.nodes.size(), false);
  std::vector<std::pair<int, Mat4>> stack;
  for (int r : root_nodes(m)) stack.emplace_back(r, Mat4(1.0f));
  std::reverse(stack.begin(), stack.end());
  while (!stack.empty()) {
    auto [index, parent] = stack.back();
    stack.pop_back();
    if (index < 0 || static_cast<size_t>(index) >= m.nodes.size())
      fail(name, "node " + format_number(index) + " does not exist");
    if (visited[index]) fail(name, "node " + format_number(index) + " is reached twice (cycle)");
    visited[index] = true;
    const tinygltf::Node& node = m.nodes[index];
    const Mat4 world = parent * local_matrix(node, name + ": node " + std::to_string(index));
    if (node.mesh >= 0) {
      for (Object& object : objects_of_node(m, index, world, name, table)) {
        if (object.mesh.triangle_count() == 0) continue;
        object.id = first_id + static_cast<ObjectId>(objects.size());
        finish_object(object, name + ": node " + std::to_string(index));
        objects.push_back(std::move(object));
      }
    }
    for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) stack.emplace_back(*c, world);
  }
  return {std::move(objects), std::move(table.textures)};
}

}  // namespace cellwalk::detail
