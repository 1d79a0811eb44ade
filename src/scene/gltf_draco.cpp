// KHR_draco_mesh_compression for the glTF reader: each compressed primitive's Draco stream is
// decoded with Debian's libdraco into plain accessors (float attributes, 32-bit indices) of an
// equivalent GLB, which the reader then reads as any other (gltf_container.hpp). New accessors
// are made rather than the primitive's own rewritten, as two primitives may share those.
#include <draco/compression/decode.h>

#include "cellwalk/core/error.hpp"
#include "scene/gltf_container.hpp"

namespace cellwalk::detail {

namespace {

constexpr const char* kName = "KHR_draco_mesh_compression";

const Json* draco_of(const Json& primitive) {
  if (!primitive.is_object() || !primitive.contains("extensions") || !primitive["extensions"].is_object()) return nullptr;
  const Json& e = primitive["extensions"];
  return e.contains(kName) && e[kName].is_object() ? &e[kName] : nullptr;
}

template <class F>
void for_each_primitive(Json& doc, F&& f) {
  if (!doc.contains("meshes") || !doc["meshes"].is_array()) return;
  for (size_t m = 0; m < doc["meshes"].size(); ++m) {
    Json& mesh = doc["meshes"][m];
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
    for (size_t p = 0; p < mesh["primitives"].size(); ++p) f(mesh["primitives"][p], "mesh " + std::to_string(m) + " primitive " + std::to_string(p));
  }
}

std::unique_ptr<draco::Mesh> decode_stream(std::span<const uint8_t> data, const std::string& where) {
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data.data()), data.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok())
    fail(where, std::string("the Draco data does not decode (") + decoded.status().error_msg() +
                    "); the file is damaged: re-export it, or without Draco compression");
  return std::move(decoded).value();
}

// A new accessor of `doc` like `like` (its type, min, max, name) over `view`: `count` elements of
// `component_type`.
uint64_t add_accessor(Json& doc, const Json& like, uint64_t view, uint64_t count, int component_type) {
  Json a = like;
  a["bufferView"] = view;
  a["byteOffset"] = 0;
  a["count"] = count;
  a["componentType"] = component_type;
  a.erase("normalized");
  a.erase("sparse");
  doc["accessors"].push_back(a);
  return doc["accessors"].size() - 1;
}

const Json& accessor_at(const Json& doc, const Json& index, const std::string& where) {
  if (!index.is_number_unsigned() || !doc.contains("accessors") || !doc["accessors"].is_array() ||
      index.get<uint64_t>() >= doc["accessors"].size() || !doc["accessors"][index.get<size_t>()].is_object())
    fail(where, "names an accessor that does not exist");
  return doc["accessors"][index.get<size_t>()];
}

int components_of(const Json& accessor) {
  if (!accessor.contains("type") || !accessor["type"].is_string()) return 0;
  const std::string type = accessor["type"].get<std::string>();
  return type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : type == "VEC4" ? 4 : 0;
}

// Replaces the primitive's indices and the attributes the extension names with accessors of the
// decoded mesh's faces and points.
void decode_primitive(Json& doc, Json& primitive, GlbWriter& out, const std::string& where) {
  const Json ext = *draco_of(primitive);
  // Draco compresses triangles (lists or strips) and decodes to a list; points and lines are
  // skipped by the reader, so their streams are not decoded.
  const Json mode = primitive.contains("mode") ? primitive["mode"] : Json(4);
  if (mode != 4 && mode != 5) {
    primitive["extensions"].erase(kName);
    return;
  }
  primitive["mode"] = 4;
  if (doc.contains("accessors") && !doc["accessors"].is_array()) fail(where, "the file's accessors are not a list");
  const uint64_t view = whole(ext, "bufferView", 0, where, true);
  if (view >= doc["bufferViews"].size()) fail(where, "names bufferView " + std::to_string(view) + ", which does not exist");
  const std::unique_ptr<draco::Mesh> mesh = decode_stream(out.view_bytes(doc["bufferViews"][view], where), where);
  const uint64_t points = mesh->num_points();

  std::vector<uint32_t> indices;
  indices.reserve(size_t(mesh->num_faces()) * 3);
  for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f)
    for (int c = 0; c < 3; ++c) indices.push_back(mesh->face(f)[c].value());
  const Json index_like = primitive.contains("indices") ? accessor_at(doc, primitive["indices"], where)
                                                        : Json{{"type", "SCALAR"}};
  const uint64_t index_view = out.add_view(doc, {reinterpret_cast<const uint8_t*>(indices.data()), indices.size() * 4}, where);
  primitive["indices"] = add_accessor(doc, index_like, index_view, indices.size(), 5125);

  if (!ext.contains("attributes") || !ext["attributes"].is_object()) fail(where, "the Draco extension has no attributes");
  if (!primitive.contains("attributes") || !primitive["attributes"].is_object()) fail(where, "has no attributes");
  for (const auto& [semantic, id] : ext["attributes"].items()) {
    const std::string at = where + " attribute " + semantic;
    if (!id.is_number_unsigned() || id.get<uint64_t>() > UINT32_MAX) fail(at, "the Draco attribute id is not a whole number");
    const draco::PointAttribute* attribute = mesh->GetAttributeByUniqueId(id.get<uint32_t>());
    if (!attribute) fail(at, "names Draco attribute " + std::to_string(id.get<uint64_t>()) + ", which the stream does not have");
    if (!primitive["attributes"].contains(semantic)) fail(at, "is compressed but the primitive has no accessor for it");
    const Json& like = accessor_at(doc, primitive["attributes"][semantic], at);
    const int n = components_of(like);
    if (n == 0) fail(at, "the accessor's type is not SCALAR, VEC2, VEC3 or VEC4; the file breaks the glTF schema: re-export it");
    if (n != attribute->num_components())
      fail(at, "the accessor has " + std::to_string(n) + " components but the Draco attribute " +
                   std::to_string(attribute->num_components()) + "; the file is inconsistent: re-export it");
    std::vector<float> values(points * n);
    for (uint32_t i = 0; i < points; ++i) {
      const draco::AttributeValueIndex value = attribute->mapped_index(draco::PointIndex(i));
      if (value.value() >= attribute->size() ||
          !attribute->ConvertValue<float>(value, int8_t(n), &values[size_t(i) * n]))
        fail(at, "a point's value is missing from the Draco attribute; the file is damaged: re-export it");
    }
    const uint64_t v = out.add_view(doc, {reinterpret_cast<const uint8_t*>(values.data()), values.size() * 4}, at);
    primitive["attributes"][semantic] = add_accessor(doc, like, v, points, 5126);
  }
  primitive["extensions"].erase(kName);
}

}  // namespace

std::vector<uint8_t> decode_draco_compression(Bytes file, bool glb, const std::string& name, const std::string& base_dir) {
  Json doc = gltf_json(file, glb);
  if (!doc.is_object()) return {};
  bool used = false;
  for_each_primitive(doc, [&used](const Json& primitive, const std::string&) { used |= draco_of(primitive) != nullptr; });
  if (!used) return {};
  if (!doc.contains("bufferViews") || !doc["bufferViews"].is_array()) fail(name, "Draco-compressed primitives but no buffer views");

  GlbWriter out(gltf_buffers(doc, file, glb, name, base_dir));
  // The streams are read through the file's own views, before those are rebased; the views
  // appended after them already point into the chunk.
  const size_t file_views = doc["bufferViews"].size();
  for_each_primitive(doc, [&](Json& primitive, const std::string& where) {
    if (draco_of(primitive)) decode_primitive(doc, primitive, out, name + ": " + where);
  });
  for (size_t v = 0; v < file_views; ++v) out.rebase(doc["bufferViews"][v], name + ": bufferView " + std::to_string(v));
  remove_extension_names(doc, {kName});
  return out.finish(std::move(doc), name);
}

}  // namespace cellwalk::detail
