// Meshes resident on the GPU, keyed by (object, lod), kept under a byte budget with
// least-recently-used eviction. The renderer draws from here; the store's budget on the CPU
// side is separate.
#pragma once

#include <cstdint>
#include <functional>
#include <list>
#include <unordered_map>
#include <utility>

#include "cellwalk/scene/mesh.hpp"

namespace cellwalk::render {

// One mesh in one GL buffer: interleaved vertices (position float3, normal packed
// 2_10_10_10 snorm, then colour RGBA8 only when the mesh has colours, then uv float2 only when
// it samples a texture), then 32-bit indices.
// REQUIRES: a current GL context for the lifetime of the object.
class GpuMesh {
 public:
  // Bytes the buffer for `mesh` takes: what budgets count.
  static uint64_t bytes_for(const Mesh& mesh);
  // Uploads `mesh`, computing normals when it has none. REQUIRES: `mesh` passes validate().
  explicit GpuMesh(const Mesh& mesh);
  ~GpuMesh();
  GpuMesh(GpuMesh&& other) noexcept;
  GpuMesh& operator=(GpuMesh&&) = delete;
  GpuMesh(const GpuMesh&) = delete;
  GpuMesh& operator=(const GpuMesh&) = delete;

  uint32_t buffer() const { return buffer_; }
  uint64_t bytes() const { return bytes_; }
  uint32_t stride() const { return stride_; }
  bool has_colors() const { return has_colors_; }
  // The texture the mesh samples (kNoTexture: none), and its uvs' offset in each vertex.
  uint32_t texture() const { return texture_; }
  uint32_t uv_offset() const { return uv_offset_; }
  uint64_t index_offset() const { return index_offset_; }
  uint32_t index_count() const { return index_count_; }

 private:
  uint32_t buffer_ = 0;
  uint64_t bytes_ = 0;
  uint32_t stride_ = 0;
  bool has_colors_ = false;
  uint32_t texture_ = kNoTexture;
  uint32_t uv_offset_ = 0;
  uint64_t index_offset_ = 0;
  uint32_t index_count_ = 0;
};

// A draw item's kind, id and level (cellwalk/render/renderer.hpp, DrawKind).
struct MeshKey {
  uint32_t id = 0;
  uint32_t lod = 0;
  uint8_t kind = 0;
  bool operator==(const MeshKey&) const = default;
};

struct MeshKeyHash {
  size_t operator()(const MeshKey& key) const {
    return std::hash<uint64_t>()((uint64_t(key.kind) << 60) ^ (uint64_t(key.id) << 28) ^ key.lod);
  }
};

// Invariant: held_bytes() <= budget() at every moment, including during an insert (room is made
// before the upload), except while one mesh larger than the whole budget is drawn from a
// transient buffer with nothing else held. Deleting a buffer that a queued draw still reads is
// safe in GL: the name dies at once, the storage lives until the commands using it complete
// (OpenGL 4.5 core §5.1.3). So buffers evicted (or drawn transiently) in the current frame still
// hold memory — host memory on llvmpipe — until the GPU finishes: they are counted as retired,
// and when the budget needs their room the cache waits for the GPU (glFinish) to free them.
class GpuMeshCache {
 public:
  explicit GpuMeshCache(uint64_t budget_bytes) : budget_(budget_bytes) {}

  // The resident mesh for `key`, now the most recently used; nullptr when not resident.
  const GpuMesh* find(const MeshKey& key);
  // Evicts least recently used meshes until `mesh` fits, then uploads and keeps it.
  // REQUIRES: `key` is not resident and GpuMesh::bytes_for(mesh) <= budget().
  const GpuMesh* insert(const MeshKey& key, const Mesh& mesh);
  // Room for a transient buffer of `bytes` (which may exceed the budget: then nothing else stays
  // held), and, once the caller has queued its draw, counts it retired.
  void make_room(uint64_t bytes);
  void retire(uint64_t bytes) { retired_bytes_ += bytes; }
  // The GPU has finished every queued command (the renderer calls glFinish): retired storage is free.
  void gpu_finished() { retired_bytes_ = 0; }

  uint64_t budget() const { return budget_; }
  // A new budget; a smaller one evicts least recently used meshes until they fit.
  // REQUIRES: the GPU has finished (no retired storage).
  void set_budget(uint64_t bytes);
  uint64_t resident_bytes() const { return resident_bytes_; }
  // Resident plus retired: the memory the cache's buffers take now.
  uint64_t held_bytes() const { return resident_bytes_ + retired_bytes_; }
  size_t size() const { return entries_.size(); }

 private:
  using Entries = std::list<std::pair<MeshKey, GpuMesh>>;  // front = most recently used

  void evict_least_recent();

  uint64_t budget_;
  uint64_t resident_bytes_ = 0;
  uint64_t retired_bytes_ = 0;
  Entries entries_;
  std::unordered_map<MeshKey, Entries::iterator, MeshKeyHash> index_;
};

}  // namespace cellwalk::render
