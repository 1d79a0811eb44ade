// GltfWriter: glTF 2.0 export, ".gltf" + ".bin" beside it, or one ".glb". One mesh, node and
// material (baseColorFactor = object colour) per object; POSITION, NORMAL, COLOR_0 (RGBA8
// normalized) and uint32 indices. The binary data streams to disk as objects arrive; only the
// JSON, a few hundred bytes per object, is held until finish().
#include <bit>
#include <filesystem>
#include <optional>
#include <string_view>

#include <nlohmann/json.hpp>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"

namespace cellwalk {

// Vertex data is written as it lies in memory; glTF buffers are little-endian.
static_assert(std::endian::native == std::endian::little);

namespace {

constexpr int kFloat = 5126, kUnsignedByte = 5121, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

double unit(Rgba8 c, int shift) { return ((c >> shift) & 0xff) / 255.0; }

}  // namespace

struct GltfWriter::Impl {
  std::string path;
  bool glb = false;
  std::string bin_name;  // the .bin's file name, for the buffer's uri
  std::optional<AtomicFile> bin;  // for a .glb a scratch file, never committed
  nlohmann::json accessors = nlohmann::json::array(), views = nlohmann::json::array(),
                 meshes = nlohmann::json::array(), nodes = nlohmann::json::array(),
                 materials = nlohmann::json::array();

  // Writes `bytes` as a new buffer view (4-byte aligned, as glTF asks) and an accessor on it.
  int add_accessor(const void* data, size_t bytes, size_t count, const char* type,
                   int component_type, int target, nlohmann::json extra = {}) {
    const uint64_t offset = bin->size();
    bin->write(std::span(static_cast<const uint8_t*>(data), bytes));
    bin->write(std::string_view("\0\0\0", (4 - bytes % 4) % 4));
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", target}});
    nlohmann::json a = {{"bufferView", views.size() - 1}, {"componentType", component_type},
                        {"count", count}, {"type", type}};
    if (!extra.is_null()) a.update(extra);
    accessors.push_back(std::move(a));
    return static_cast<int>(accessors.size() - 1);
  }

  nlohmann::json document() const {
    nlohmann::json scene_nodes = nlohmann::json::array();
    for (size_t i = 0; i < nodes.size(); ++i) scene_nodes.push_back(i);
    nlohmann::json doc = {{"asset", {{"version", "2.0"}, {"generator", "cellwalk"}}},
                          {"scene", 0},
                          {"scenes", {{{"nodes", scene_nodes}}}},
                          {"nodes", nodes}};
    if (!meshes.empty()) {
      nlohmann::json buffer = {{"byteLength", bin->size()}};
      if (!glb) buffer["uri"] = bin_name;
      doc.update({{"meshes", meshes}, {"materials", materials}, {"accessors", accessors},
                  {"bufferViews", views}, {"buffers", {buffer}}});
    }
    return doc;
  }
};

GltfWriter::GltfWriter(std::string path) : impl_(std::make_unique<Impl>()) {
  const std::filesystem::path p(path);
  impl_->glb = p.extension() == ".glb";
  impl_->bin_name = p.stem().string() + ".bin";
  // A .glb's binary chunk is staged in a scratch file and copied in after the JSON chunk, whose
  // size is known only at the end; the scratch is never committed, so nothing of it remains.
  impl_->bin.emplace(impl_->glb ? path + ".bin" : (p.parent_path() / impl_->bin_name).string());
  impl_->path = std::move(path);
}

GltfWriter::~GltfWriter() = default;

void GltfWriter::add(const Object& object) {
  Impl& w = *impl_;
  const Mesh& m = object.mesh;
  nlohmann::json node = {{"name", object.name}};
  if (m.triangle_count() > 0) {  // glTF accessors may not be empty
    const Aabb box = bounds_of(m);
    nlohmann::json attributes = {
        {"POSITION",
         w.add_accessor(m.positions.data(), m.positions.size() * sizeof(Vec3), m.positions.size(),
                        "VEC3", kFloat, kArrayBuffer,
                        {{"min", {box.min.x, box.min.y, box.min.z}},
                         {"max", {box.max.x, box.max.y, box.max.z}}})}};
    if (!m.normals.empty())
      attributes["NORMAL"] = w.add_accessor(m.normals.data(), m.normals.size() * sizeof(Vec3),
                                            m.normals.size(), "VEC3", kFloat, kArrayBuffer);
    if (!m.colors.empty())
      attributes["COLOR_0"] =
          w.add_accessor(m.colors.data(), m.colors.size() * sizeof(Rgba8), m.colors.size(), "VEC4",
                         kUnsignedByte, kArrayBuffer, {{"normalized", true}});
    const int indices = w.add_accessor(m.indices.data(), m.indices.size() * sizeof(uint32_t),
                                       m.indices.size(), "SCALAR", kUnsignedInt, kElementArrayBuffer);
    const Rgba8 c = object.color;
    w.materials.push_back(
        {{"pbrMetallicRoughness",
          {{"baseColorFactor", {unit(c, 0), unit(c, 8), unit(c, 16), unit(c, 24)}}}}});
    w.meshes.push_back({{"name", object.name},
                        {"primitives",
                         {{{"attributes", attributes},
                           {"indices", indices},
                           {"material", w.materials.size() - 1},
                           {"mode", 4}}}}});
    node["mesh"] = w.meshes.size() - 1;
  }
  w.nodes.push_back(std::move(node));
}

namespace {

void write_u32(AtomicFile& out, uint32_t v) {
  out.write(std::string_view(reinterpret_cast<const char*>(&v), sizeof v));
}

// GLB: 12-byte header, then a JSON chunk and a BIN chunk, each padded to 4 bytes.
void write_glb(const std::string& path, std::string json, AtomicFile& bin) {
  json.append((4 - json.size() % 4) % 4, ' ');
  const uint64_t total = 12 + 8 + json.size() + (bin.size() > 0 ? 8 + bin.size() : 0);
  if (total > UINT32_MAX) fail(path, "GLB larger than 4 GiB; write .gltf instead");
  AtomicFile out(path);
  out.write("glTF");
  write_u32(out, 2);
  write_u32(out, static_cast<uint32_t>(total));
  write_u32(out, static_cast<uint32_t>(json.size()));
  out.write("JSON");
  out.write(json);
  if (bin.size() > 0) {
    write_u32(out, static_cast<uint32_t>(bin.size()));
    out.write(std::string_view("BIN\0", 4));
    out.append_contents_of(bin);
  }
  out.commit();
}

}  // namespace

void GltfWriter::finish() {
  Impl& w = *impl_;
  const std::string json = w.document().dump();
  if (w.glb) {
    write_glb(w.path, json, *w.bin);
    w.bin.reset();  // removes the scratch file
    return;
  }
  w.bin->commit();
  write_file_atomically(w.path, json);
}

}  // namespace cellwalk
