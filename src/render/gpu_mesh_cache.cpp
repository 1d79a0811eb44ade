// The GPU mesh cache: one buffer per (object, lod), LRU under a byte budget.
#include "render/gpu_mesh_cache.hpp"

#include <epoxy/gl.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <optional>

namespace cellwalk::render {
namespace {

constexpr uint32_t kPositionBytes = 12;
constexpr uint32_t kNormalBytes = 4;
constexpr uint32_t kColorBytes = 4;
constexpr uint32_t kUvBytes = 8;

// Uvs are uploaded only for a mesh that samples a texture: the others would never read them.
bool textured(const Mesh& mesh) { return mesh.texture != kNoTexture; }

uint32_t uv_offset_for(const Mesh& mesh) {
  return kPositionBytes + kNormalBytes + (mesh.colors.empty() ? 0 : kColorBytes);
}

uint32_t stride_for(const Mesh& mesh) { return uv_offset_for(mesh) + (textured(mesh) ? kUvBytes : 0); }

uint32_t snorm10(float v) {
  return uint32_t(int32_t(std::lround(std::clamp(v, -1.0f, 1.0f) * 511.0f))) & 0x3FFu;
}

// GL_INT_2_10_10_10_REV: x in the low bits, w (unused) in the top two.
uint32_t pack_normal(const Vec3& n) {
  return snorm10(n.x) | snorm10(n.y) << 10 | snorm10(n.z) << 20;
}

void interleave(const Mesh& mesh, const std::vector<Vec3>& normals, uint32_t stride, uint8_t* out) {
  for (size_t i = 0; i < mesh.positions.size(); ++i, out += stride) {
    std::memcpy(out, &mesh.positions[i], kPositionBytes);
    uint32_t normal = pack_normal(normals[i]);
    std::memcpy(out + kPositionBytes, &normal, kNormalBytes);
    if (!mesh.colors.empty()) {
      std::memcpy(out + kPositionBytes + kNormalBytes, &mesh.colors[i], kColorBytes);
    }
    if (textured(mesh)) std::memcpy(out + uv_offset_for(mesh), &mesh.uvs[i], kUvBytes);
  }
}

}  // namespace

uint64_t GpuMesh::bytes_for(const Mesh& mesh) {
  return uint64_t(stride_for(mesh)) * mesh.positions.size() +
         sizeof(uint32_t) * mesh.indices.size();
}

GpuMesh::GpuMesh(const Mesh& mesh)
    : bytes_(bytes_for(mesh)),
      stride_(stride_for(mesh)),
      has_colors_(!mesh.colors.empty()),
      texture_(mesh.texture),
      uv_offset_(uv_offset_for(mesh)),
      index_offset_(uint64_t(stride_) * mesh.positions.size()),
      index_count_(uint32_t(mesh.indices.size())) {
  // Meshes without normals get smooth ones so they are lit like the rest.
  std::optional<Mesh> with_normals;
  if (mesh.normals.empty()) {
    with_normals = mesh;
    compute_normals(*with_normals);
  }
  const std::vector<Vec3>& normals = with_normals ? with_normals->normals : mesh.normals;

  // Written in place through a mapping: no CPU staging copy as large as the mesh.
  // GL refuses zero-sized storage; an empty mesh still gets a (never drawn) one-byte buffer.
  GLsizeiptr size = GLsizeiptr(std::max<uint64_t>(bytes_, 1));
  glCreateBuffers(1, &buffer_);
  glNamedBufferStorage(buffer_, size, nullptr, GL_MAP_WRITE_BIT);
  auto* out = static_cast<uint8_t*>(
      glMapNamedBufferRange(buffer_, 0, size, GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT));
  interleave(mesh, normals, stride_, out);
  // REQUIRES a non-null source even for zero bytes: an empty mesh's vector may have none.
  if (!mesh.indices.empty()) {
    std::memcpy(out + index_offset_, mesh.indices.data(), sizeof(uint32_t) * mesh.indices.size());
  }
  glUnmapNamedBuffer(buffer_);
}

GpuMesh::~GpuMesh() {
  if (buffer_ != 0) glDeleteBuffers(1, &buffer_);
}

GpuMesh::GpuMesh(GpuMesh&& other) noexcept
    : buffer_(std::exchange(other.buffer_, 0)),
      bytes_(other.bytes_),
      stride_(other.stride_),
      has_colors_(other.has_colors_),
      texture_(other.texture_),
      uv_offset_(other.uv_offset_),
      index_offset_(other.index_offset_),
      index_count_(other.index_count_) {}

const GpuMesh* GpuMeshCache::find(const MeshKey& key) {
  auto it = index_.find(key);
  if (it == index_.end()) return nullptr;
  entries_.splice(entries_.begin(), entries_, it->second);
  return &it->second->second;
}

const GpuMesh* GpuMeshCache::insert(const MeshKey& key, const Mesh& mesh) {
  assert(index_.count(key) == 0);
  uint64_t bytes = GpuMesh::bytes_for(mesh);
  assert(bytes <= budget_);
  make_room(bytes);
  entries_.emplace_front(key, GpuMesh(mesh));
  index_.emplace(key, entries_.begin());
  resident_bytes_ += bytes;
  return &entries_.front().second;
}

void GpuMeshCache::make_room(uint64_t bytes) {
  if (held_bytes() + bytes <= budget_) return;
  // Evicting moves bytes from resident to retired: room appears once the GPU has finished, so
  // each wait frees a quarter of the budget beyond what this mesh needs, and the next inserts
  // fill it without waiting again.
  const uint64_t target = budget_ - std::min(budget_, budget_ / 4 + bytes);
  while (resident_bytes_ > target && !entries_.empty()) evict_least_recent();
  if (held_bytes() + bytes > budget_ && retired_bytes_ > 0) {
    glFinish();  // queued draws release the evicted buffers' storage
    gpu_finished();
  }
}

void GpuMeshCache::set_budget(uint64_t bytes) {
  budget_ = bytes;
  while (resident_bytes_ > budget_ && !entries_.empty()) evict_least_recent();
}

void GpuMeshCache::evict_least_recent() {
  assert(!entries_.empty());
  retired_bytes_ += entries_.back().second.bytes();
  resident_bytes_ -= entries_.back().second.bytes();
  index_.erase(entries_.back().first);
  entries_.pop_back();
}

}  // namespace cellwalk::render
