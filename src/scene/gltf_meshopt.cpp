// EXT_meshopt_compression (and its ratified name KHR_meshopt_compression) for the glTF reader:
// the compressed buffer views that gltfpack -c / -cc writes are decoded with meshoptimizer
// (meshopt_decodeVertexBuffer / IndexBuffer / IndexSequence and the octahedral, quaternion and
// exponential filters) into an equivalent uncompressed GLB, which the reader then reads as any
// other. Every offset, length, stride and count is checked against the bytes it names before
// anything is decoded or allocated.
#include <meshoptimizer.h>

#include "cellwalk/core/error.hpp"
#include "scene/gltf_container.hpp"

namespace cellwalk::detail {

namespace {

constexpr const char* kNames[] = {"EXT_meshopt_compression", "KHR_meshopt_compression"};

// The extension object of `j` under either name, or null.
const Json* meshopt_of(const Json& j) {
  if (!j.is_object() || !j.contains("extensions") || !j["extensions"].is_object()) return nullptr;
  for (const char* n : kNames)
    if (j["extensions"].contains(n) && j["extensions"][n].is_object()) return &j["extensions"][n];
  return nullptr;
}

void decode_filter(const std::string& filter, uint8_t* dst, uint64_t count, uint64_t stride, const std::string& where) {
  if (filter == "OCTAHEDRAL") {
    if (stride != 4 && stride != 8) fail(where, "OCTAHEDRAL needs a byteStride of 4 or 8");
    meshopt_decodeFilterOct(dst, count, stride);
  } else if (filter == "QUATERNION") {
    if (stride != 8) fail(where, "QUATERNION needs a byteStride of 8");
    meshopt_decodeFilterQuat(dst, count, stride);
  } else if (filter == "EXPONENTIAL") {
    meshopt_decodeFilterExp(dst, count, stride);
  } else if (filter != "NONE") {
    fail(where, "filter '" + filter + "' is not NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL");
  }
}

// Decodes one compressed view onto the end of the writer's chunk and returns where it starts.
uint64_t decode_view(const Json& ext, GlbWriter& out, const std::string& where) {
  const uint64_t stride = whole(ext, "byteStride", 0, where, true), count = whole(ext, "count", 0, where, true);
  const auto text = [&ext](const char* key, const char* fallback) {
    return ext.contains(key) && ext[key].is_string() ? ext[key].get<std::string>() : std::string(fallback);
  };
  const std::string mode = text("mode", ""), filter = text("filter", "NONE");
  const std::span<const uint8_t> src = out.view_bytes(ext, where);
  if (stride == 0 || stride > 256 || count > (uint64_t(4) << 30) / stride) fail(where, "byteStride or count out of range");
  // The source lies in the same chunk: copied first, as appending may move it.
  const std::vector<uint8_t> data(src.begin(), src.end());
  const uint64_t at = out.append(count * stride, where);
  uint8_t* dst = out.bin().data() + at;
  int rc = -1;
  if (mode == "ATTRIBUTES") {
    if (stride % 4 != 0) fail(where, "ATTRIBUTES with a byteStride that is not a multiple of 4");
    rc = meshopt_decodeVertexBuffer(dst, count, stride, data.data(), data.size());
  } else if (mode == "TRIANGLES" || mode == "INDICES") {
    if (stride != 2 && stride != 4) fail(where, mode + " with a byteStride other than 2 or 4");
    if (mode == "TRIANGLES" && count % 3 != 0) fail(where, "TRIANGLES with a count not a multiple of 3");
    rc = mode == "TRIANGLES" ? meshopt_decodeIndexBuffer(dst, count, stride, data.data(), data.size())
                             : meshopt_decodeIndexSequence(dst, count, stride, data.data(), data.size());
  } else {
    fail(where, "mode '" + mode + "' is not ATTRIBUTES, TRIANGLES or INDICES");
  }
  if (rc != 0) fail(where, "the compressed data does not decode (meshoptimizer error " + std::to_string(rc) + ")");
  if (filter != "NONE" && mode != "ATTRIBUTES") fail(where, "a filter on " + mode);
  decode_filter(filter, dst, count, stride, where);
  return at;
}

}  // namespace

std::vector<uint8_t> decode_meshopt_compression(Bytes file, bool glb, const std::string& name, const std::string& base_dir) {
  Json doc = gltf_json(file, glb);
  if (!doc.is_object() || !doc.contains("bufferViews") || !doc["bufferViews"].is_array()) return {};
  bool used = false;
  for (const Json& view : doc["bufferViews"]) used |= meshopt_of(view) != nullptr;
  if (!used) return {};

  GlbWriter out(gltf_buffers(doc, file, glb, name, base_dir));
  for (size_t v = 0; v < doc["bufferViews"].size(); ++v) {
    Json& view = doc["bufferViews"][v];
    const std::string where = name + ": bufferView " + std::to_string(v);
    if (!view.is_object()) fail(where, "is not an object");
    if (const Json* ext = meshopt_of(view)) {
      const Json e = *ext;
      view["byteOffset"] = decode_view(e, out, where);
      view["buffer"] = 0;
      view["byteLength"] = e["count"].get<uint64_t>() * e["byteStride"].get<uint64_t>();
      for (const char* n : kNames) view["extensions"].erase(n);
    } else {
      out.rebase(view, where);
    }
  }
  remove_extension_names(doc, {kNames[0], kNames[1]});
  return out.finish(std::move(doc), name);
}

}  // namespace cellwalk::detail
