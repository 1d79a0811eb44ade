// The glTF document, its buffers and the equivalent-GLB writer the extension decoders share
// (gltf_container.hpp).
#include "scene/gltf_container.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <optional>

#include "cellwalk/core/error.hpp"

namespace cellwalk::detail {

namespace {

constexpr uint64_t kMaxChunkBytes = uint64_t(4) << 30;
constexpr uint32_t kJsonChunk = 0x4E4F534Au, kBinChunk = 0x004E4942u;

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

bool is_fallback(const Json& buffer) {
  if (!buffer.contains("extensions") || !buffer["extensions"].is_object()) return false;
  for (const char* n : {"EXT_meshopt_compression", "KHR_meshopt_compression"}) {
    const Json& e = buffer["extensions"];
    if (e.contains(n) && e[n].is_object() && e[n].contains("fallback") && e[n]["fallback"] == true) return true;
  }
  return false;
}

std::vector<uint8_t> buffer_bytes(const Json& buffer, size_t i, std::optional<Bytes> bin, const std::string& name,
                                  const std::string& base_dir) {
  const std::string where = name + ": buffer " + std::to_string(i);
  if (!buffer.is_object()) fail(where, "is not an object");
  if (is_fallback(buffer)) return {};
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

}  // namespace

Json gltf_json(Bytes file, bool glb) {
  std::string_view text(reinterpret_cast<const char*>(file.data()), file.size());
  if (glb) text = file.size() >= 20 ? text.substr(20, le32_at(file, 12)) : std::string_view();
  return Json::parse(text.begin(), text.end(), nullptr, false);
}

std::vector<std::vector<uint8_t>> gltf_buffers(const Json& doc, Bytes file, bool glb, const std::string& name,
                                               const std::string& base_dir) {
  if (!doc.contains("buffers") || !doc["buffers"].is_array()) fail(name, "has buffer views but no buffers");
  std::optional<Bytes> bin;
  if (glb) {  // framing already checked: chunk 0 is JSON; a BIN chunk may follow it
    const size_t next = 20 + size_t(le32_at(file, 12));
    if (next + 8 <= file.size() && le32_at(file, next + 4) == kBinChunk)
      bin = file.subspan(next + 8, std::min<size_t>(le32_at(file, next), file.size() - next - 8));
  }
  std::vector<std::vector<uint8_t>> buffers;
  for (size_t i = 0; i < doc["buffers"].size(); ++i) buffers.push_back(buffer_bytes(doc["buffers"][i], i, bin, name, base_dir));
  return buffers;
}

uint64_t whole(const Json& j, const char* key, uint64_t fallback, const std::string& where, bool required) {
  if (!j.is_object()) fail(where, "is not an object");
  if (!j.contains(key)) {
    if (required) fail(where, std::string("has no ") + key);
    return fallback;
  }
  if (!j[key].is_number_unsigned()) fail(where, std::string(key) + " is not a whole number");
  return j[key].get<uint64_t>();
}

void remove_extension_names(Json& doc, std::initializer_list<const char*> names) {
  for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
    if (!doc.contains(list) || !doc[list].is_array()) continue;
    Json kept = Json::array();
    for (const Json& e : doc[list])
      if (!e.is_string() || std::none_of(names.begin(), names.end(), [&e](const char* n) { return e == n; })) kept.push_back(e);
    doc[list] = kept;
  }
}

GlbWriter::GlbWriter(const std::vector<std::vector<uint8_t>>& buffers) {
  for (const std::vector<uint8_t>& b : buffers) {
    base_.push_back(bin_.size());
    size_.push_back(b.size());
    bin_.insert(bin_.end(), b.begin(), b.end());
    bin_.resize((bin_.size() + 3) / 4 * 4, 0);
  }
}

void GlbWriter::rebase(Json& view, const std::string& where) const {
  view_bytes(view, where);  // checks the view lies inside its buffer
  const uint64_t b = whole(view, "buffer", 0, where, true);
  view["buffer"] = 0;
  view["byteOffset"] = base_[b] + whole(view, "byteOffset", 0, where);
}

std::span<const uint8_t> GlbWriter::view_bytes(const Json& view, const std::string& where) const {
  const uint64_t b = whole(view, "buffer", 0, where, true);
  if (b >= base_.size()) fail(where, "names buffer " + std::to_string(b) + ", which does not exist");
  const uint64_t offset = whole(view, "byteOffset", 0, where), length = whole(view, "byteLength", 0, where, true);
  if (offset > size_[b] || length > size_[b] - offset)
    fail(where, "bytes " + std::to_string(offset) + "+" + std::to_string(length) + " run past buffer " + std::to_string(b) +
                    " (" + std::to_string(size_[b]) + " bytes)");
  return std::span<const uint8_t>(bin_).subspan(base_[b] + offset, length);
}

uint64_t GlbWriter::append(uint64_t size, const std::string& where) {
  if (size > kMaxChunkBytes || bin_.size() + size > kMaxChunkBytes)
    fail(where, "decodes to more than 4 GiB, more than a GLB can hold; split the model into smaller files");
  const uint64_t at = bin_.size();
  bin_.resize((at + size + 3) / 4 * 4, 0);
  return at;
}

uint64_t GlbWriter::add_view(Json& doc, std::span<const uint8_t> bytes, const std::string& where) {
  const std::vector<uint8_t> copy(bytes.begin(), bytes.end());  // `bytes` may lie in bin_, which append() may move
  const uint64_t at = append(copy.size(), where);
  std::copy(copy.begin(), copy.end(), bin_.begin() + at);
  doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", bytes.size()}});
  return doc["bufferViews"].size() - 1;
}

std::vector<uint8_t> GlbWriter::finish(Json doc, const std::string& name) const {
  doc["buffers"] = Json::array({{{"byteLength", bin_.size()}}});
  std::string json = doc.dump();
  json.append((4 - json.size() % 4) % 4, ' ');
  std::vector<uint8_t> result(12);
  const auto chunk = [&result](const void* data, size_t size, uint32_t type) {
    const uint32_t header[2] = {uint32_t(size), type};
    result.insert(result.end(), reinterpret_cast<const uint8_t*>(header), reinterpret_cast<const uint8_t*>(header) + 8);
    result.insert(result.end(), static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + size);
  };
  chunk(json.data(), json.size(), kJsonChunk);
  chunk(bin_.data(), bin_.size(), kBinChunk);
  if (result.size() > UINT32_MAX) fail(name, "decoded, the model is larger than a GLB can hold (4 GiB)");
  const uint32_t header[3] = {0x46546C67u, 2, uint32_t(result.size())};
  std::memcpy(result.data(), header, 12);
  return result;
}

}  // namespace cellwalk::detail
