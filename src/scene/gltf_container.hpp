// What the glTF extension decoders (gltf_meshopt.cpp, gltf_draco.cpp) share: the document and
// its buffers read from a .gltf or GLB, and a writer of the equivalent GLB they produce, every
// buffer's bytes in its one binary chunk. Every offset and length is checked against the bytes
// it names before it is used.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <initializer_list>
#include <span>
#include <string>
#include <vector>

#include "scene/readers.hpp"

namespace cellwalk::detail {

using Json = nlohmann::json;

// The JSON of a .gltf (the whole file) or of a GLB (its first chunk); a discarded value when
// it does not parse (tinygltf reports that later). REQUIRES: a GLB's framing was checked.
Json gltf_json(Bytes file, bool glb);

// The bytes of each buffer of `doc`: the GLB's binary chunk, a data: URI or a file below
// base_dir; empty for a buffer marked as a meshopt fallback (it has no data of its own).
std::vector<std::vector<uint8_t>> gltf_buffers(const Json& doc, Bytes file, bool glb, const std::string& name,
                                               const std::string& base_dir);

// The value of `key` in `j` as a whole number; `fallback` when absent unless `required`.
uint64_t whole(const Json& j, const char* key, uint64_t fallback, const std::string& where, bool required = false);

// Removes `names` from the document's extensionsUsed and extensionsRequired.
void remove_extension_names(Json& doc, std::initializer_list<const char*> names);

// The one binary chunk of the equivalent GLB: every buffer's bytes first, then whatever the
// decoder appends. Not thread-safe.
class GlbWriter {
 public:
  explicit GlbWriter(const std::vector<std::vector<uint8_t>>& buffers);

  // Points buffer view `view` into the chunk, where its buffer's bytes now lie.
  void rebase(Json& view, const std::string& where) const;
  // The bytes buffer view `view` names (checked against its buffer); valid until the next append.
  std::span<const uint8_t> view_bytes(const Json& view, const std::string& where) const;
  // Appends `size` zero bytes, padded to 4, and returns where they start; the caller fills them
  // through bin(). Fails naming `where` when the chunk would pass 4 GiB (a few bytes of
  // hostile input can claim a billion vertices).
  uint64_t append(uint64_t size, const std::string& where);
  // Appends `bytes` as a new buffer view of `doc` and returns its index.
  uint64_t add_view(Json& doc, std::span<const uint8_t> bytes, const std::string& where);
  std::vector<uint8_t>& bin() { return bin_; }

  // The GLB of `doc` (its buffers replaced by the one chunk) and the chunk.
  std::vector<uint8_t> finish(Json doc, const std::string& name) const;

 private:
  std::vector<uint8_t> bin_;
  std::vector<uint64_t> base_, size_;  // where each buffer's bytes start in bin_, and how many
};

}  // namespace cellwalk::detail
