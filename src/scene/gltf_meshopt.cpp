// EXT_meshopt_compression (and its ratified name KHR_meshopt_compression) for the glTF reader:
// the compressed buffer views that gltfpack -c / -cc writes are decoded with meshoptimizer
// (meshopt_decodeVertexBuffer / IndexBuffer / IndexSequence and the octahedral, quaternion and
// exponential filters) into an equivalent uncompressed GLB, which the reader then reads as any
// other. Every offset, length, stride and count is checked against the bytes it names before
// anything is decoded or allocated.
#include <meshoptimizer.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <optional>

#include "cellwalk/core/error.hpp"
#include "scene/readers.hpp"

namespace cellwalk::detail {

namespace {

using Json = nlohmann::json;

constexpr const char* kNames[] = {"EXT_meshopt_compression", "KHR_meshopt_compression"};
// The most bytes the decoded views may add together, against a file of a few bytes that
// claims a billion vertices.
constexpr uint64_t kMaxDecodedBytes = uint64_t(4) << 30;

uint32_t le32_at(Bytes b, size_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// RFC 4648 base64 (padding optional); fails on any other character.
std::vector<uint8_t> base64_decode(std::string_view text, const std::string& where) {
  std::vector<uint8_t> out;
  uint32_t bits = 0;
  int held = 0;
  for (char c : text) {
    int v = c >= 'A' && c <= 'Z' ? c - 'A' : c >= 'a' && c <= 'z' ? c - 'a' + 26 : c >= '0' && c <= '9' ? c - '0' + 52
            : c == '+' ? 62 : c == '/' ? 63 : c == '=' ? -2 : -1;
    if (v == -2) break;
    if (v < 0) fail(where, "a data: uri with a character that is not base64");
    bits = bits << 6 | uint32_t(v);
    if ((held += 6) >= 8) {
      held -= 8;
      out.push_back(uint8_t(bits >> held));
    }
  }
  return out;
}

// The extension object of `j` under either name, or null.
const Json* meshopt_of(const Json& j) {
  if (!j.is_object() || !j.contains("extensions") || !j["extensions"].is_object()) return nullptr;
  for (const char* n : kNames)
    if (j["extensions"].contains(n) && j["extensions"][n].is_object()) return &j["extensions"][n];
  return nullptr;
}

uint64_t whole(const Json& j, const char* key, uint64_t fallback, const std::string& where, bool required = false) {
  if (!j.contains(key)) {
    if (required) fail(where, std::string("has no ") + key);
    return fallback;
  }
  if (!j[key].is_number_unsigned()) fail(where, std::string(key) + " is not a whole number");
  return j[key].get<uint64_t>();
}

// The bytes of buffer `i`: the GLB's BIN chunk, a data: URI, or a file below base_dir; empty
// for a fallback buffer (it has no data of its own).
std::vector<uint8_t> buffer_bytes(const Json& buffer, size_t i, std::optional<Bytes> bin, const std::string& name,
                                  const std::string& base_dir) {
  const std::string where = name + ": buffer " + std::to_string(i);
  if (const Json* ext = meshopt_of(buffer); ext && ext->value("fallback", false)) return {};
  if (!buffer.contains("uri")) {
    if (i != 0 || !bin) fail(where, "has no uri and no GLB binary chunk");
    return {bin->begin(), bin->end()};
  }
  if (!buffer["uri"].is_string()) fail(where, "uri is not a string");
  const std::string uri = buffer["uri"].get<std::string>();
  if (uri.rfind("data:", 0) == 0) {
    const size_t comma = uri.find(";base64,");
    if (comma == std::string::npos) fail(where, "a data: uri that is not base64");
    return base64_decode(std::string_view(uri).substr(comma + 8), where);
  }
  if (base_dir.empty()) fail(where, "names the file '" + uri + "', which is not read when parsing from memory");
  const auto file = (std::filesystem::path(base_dir) / uri).lexically_normal();
  const auto rel = file.lexically_relative(base_dir);
  if (rel.empty() || *rel.begin() == "..") fail(where, "names '" + uri + "', outside the model's folder");
  return read_whole_file(file.string());
}

// Decodes one compressed view into `out` (count × stride bytes appended).
void decode_view(const Json& ext, const std::vector<std::vector<uint8_t>>& buffers, const std::string& where,
                 std::vector<uint8_t>& out) {
  const uint64_t buffer = whole(ext, "buffer", 0, where, true);
  const uint64_t offset = whole(ext, "byteOffset", 0, where), length = whole(ext, "byteLength", 0, where, true);
  const uint64_t stride = whole(ext, "byteStride", 0, where, true), count = whole(ext, "count", 0, where, true);
  const std::string mode = ext.value("mode", std::string()), filter = ext.value("filter", std::string("NONE"));
  if (buffer >= buffers.size()) fail(where, "names buffer " + std::to_string(buffer) + ", which does not exist");
  const std::vector<uint8_t>& src = buffers[buffer];
  if (offset > src.size() || length > src.size() - offset)
    fail(where, "compressed bytes " + std::to_string(offset) + "+" + std::to_string(length) + " run past buffer " +
                    std::to_string(buffer) + " (" + std::to_string(src.size()) + " bytes)");
  if (stride == 0 || stride > 256 || count > kMaxDecodedBytes / stride) fail(where, "byteStride or count out of range");
  if (out.size() + count * stride > kMaxDecodedBytes) fail(where, "decodes to more than 4 GiB");
  const size_t at = out.size();
  out.resize(at + count * stride);
  uint8_t* dst = out.data() + at;
  const uint8_t* data = src.data() + offset;
  int rc = -1;
  if (mode == "ATTRIBUTES") {
    if (stride % 4 != 0) fail(where, "ATTRIBUTES with a byteStride that is not a multiple of 4");
    rc = meshopt_decodeVertexBuffer(dst, count, stride, data, length);
  } else if (mode == "TRIANGLES" || mode == "INDICES") {
    if (stride != 2 && stride != 4) fail(where, mode + " with a byteStride other than 2 or 4");
    if (mode == "TRIANGLES" && count % 3 != 0) fail(where, "TRIANGLES with a count not a multiple of 3");
    rc = mode == "TRIANGLES" ? meshopt_decodeIndexBuffer(dst, count, stride, data, length)
                             : meshopt_decodeIndexSequence(dst, count, stride, data, length);
  } else {
    fail(where, "mode '" + mode + "' is not ATTRIBUTES, TRIANGLES or INDICES");
  }
  if (rc != 0) fail(where, "the compressed data does not decode (meshoptimizer error " + std::to_string(rc) + ")");
  if (filter == "NONE") return;
  if (mode != "ATTRIBUTES") fail(where, "a filter on " + mode);
  if (filter == "OCTAHEDRAL") {
    if (stride != 4 && stride != 8) fail(where, "OCTAHEDRAL needs a byteStride of 4 or 8");
    meshopt_decodeFilterOct(dst, count, stride);
  } else if (filter == "QUATERNION") {
    if (stride != 8) fail(where, "QUATERNION needs a byteStride of 8");
    meshopt_decodeFilterQuat(dst, count, stride);
  } else if (filter == "EXPONENTIAL") {
    meshopt_decodeFilterExp(dst, count, stride);
  } else {
    fail(where, "filter '" + filter + "' is not NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL");
  }
}

void pad4(std::vector<uint8_t>& v, uint8_t with) { v.resize((v.size() + 3) / 4 * 4, with); }

void remove_name(Json& doc, const char* list) {
  if (!doc.contains(list) || !doc[list].is_array()) return;
  Json kept = Json::array();
  for (const Json& e : doc[list])
    if (!(e.is_string() && (e == kNames[0] || e == kNames[1]))) kept.push_back(e);
  doc[list] = kept;
}

}  // namespace

std::vector<uint8_t> decode_meshopt_compression(Bytes file, bool glb, const std::string& name, const std::string& base_dir) {
  std::string_view json_text(reinterpret_cast<const char*>(file.data()), file.size());
  std::optional<Bytes> bin;
  if (glb) {  // framing already checked: chunk 0 is JSON; a BIN chunk may follow it
    const uint32_t json_length = le32_at(file, 12);
    json_text = json_text.substr(20, json_length);
    const size_t next = 20 + size_t(json_length);
    if (next + 8 <= file.size() && le32_at(file, next + 4) == 0x004E4942u)
      bin = file.subspan(next + 8, std::min<size_t>(le32_at(file, next), file.size() - next - 8));
  }
  Json doc = Json::parse(json_text.begin(), json_text.end(), nullptr, false);
  if (!doc.is_object() || !doc.contains("bufferViews") || !doc["bufferViews"].is_array()) return {};
  bool used = false;
  for (const Json& view : doc["bufferViews"]) used |= meshopt_of(view) != nullptr;
  if (!used) return {};
  if (!doc.contains("buffers") || !doc["buffers"].is_array()) fail(name, "compressed buffer views but no buffers");

  std::vector<std::vector<uint8_t>> buffers;
  for (size_t i = 0; i < doc["buffers"].size(); ++i) buffers.push_back(buffer_bytes(doc["buffers"][i], i, bin, name, base_dir));
  // One new binary chunk: every buffer that has data, then each decoded view.
  std::vector<uint8_t> out;
  std::vector<uint64_t> base(buffers.size());
  for (size_t i = 0; i < buffers.size(); ++i) {
    base[i] = out.size();
    out.insert(out.end(), buffers[i].begin(), buffers[i].end());
    pad4(out, 0);
  }
  for (size_t v = 0; v < doc["bufferViews"].size(); ++v) {
    Json& view = doc["bufferViews"][v];
    const std::string where = name + ": bufferView " + std::to_string(v);
    if (!view.is_object()) fail(where, "is not an object");
    if (const Json* ext = meshopt_of(view)) {
      const Json e = *ext;
      const uint64_t at = out.size();
      decode_view(e, buffers, where, out);
      pad4(out, 0);
      view["buffer"] = 0;
      view["byteOffset"] = at;
      view["byteLength"] = e["count"].get<uint64_t>() * e["byteStride"].get<uint64_t>();
      for (const char* n : kNames) view["extensions"].erase(n);
    } else {
      const uint64_t b = whole(view, "buffer", 0, where, true);
      if (b >= buffers.size()) fail(where, "names buffer " + std::to_string(b) + ", which does not exist");
      view["buffer"] = 0;
      view["byteOffset"] = base[b] + whole(view, "byteOffset", 0, where);
    }
  }
  doc["buffers"] = Json::array({{{"byteLength", out.size()}}});
  remove_name(doc, "extensionsUsed");
  remove_name(doc, "extensionsRequired");

  std::string json = doc.dump();
  json.append((4 - json.size() % 4) % 4, ' ');
  std::vector<uint8_t> result(12);
  const auto chunk = [&result](const void* data, size_t size, uint32_t type) {
    const uint32_t header[2] = {uint32_t(size), type};
    result.insert(result.end(), reinterpret_cast<const uint8_t*>(header), reinterpret_cast<const uint8_t*>(header) + 8);
    result.insert(result.end(), static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + size);
  };
  chunk(json.data(), json.size(), 0x4E4F534Au);
  chunk(out.data(), out.size(), 0x004E4942u);
  if (result.size() > UINT32_MAX) fail(name, "decoded, the model is larger than a GLB can hold (4 GiB)");
  const uint32_t header[3] = {0x46546C67u, 2, uint32_t(result.size())};
  std::memcpy(result.data(), header, 12);
  return result;
}

}  // namespace cellwalk::detail
