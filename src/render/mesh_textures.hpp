// The GL textures meshes sample (base-colour textures, scene/texture.hpp), keyed by the
// scene's texture index and kept under a byte budget with least-recently-used eviction, like the
// mesh cache beside it. A texture is asked of the renderer's TextureSource only on a miss.
#pragma once

#include <cstdint>
#include <list>
#include <unordered_map>

#include "cellwalk/render/renderer.hpp"

namespace cellwalk::render {

// REQUIRES: a current GL context for the lifetime of the object. Deleting a texture a queued draw
// still reads is safe in GL (its storage lives until the draw completes, OpenGL 4.5 §5.1.3).
class MeshTextures {
 public:
  explicit MeshTextures(uint64_t budget_bytes) : budget_(budget_bytes) {}
  ~MeshTextures();
  MeshTextures(const MeshTextures&) = delete;
  MeshTextures& operator=(const MeshTextures&) = delete;

  // The GL texture of `index`, fetched from `source` and uploaded (evicting the least recently
  // used first) when not resident; 0 when the source has none (or gives one larger than it was
  // asked for) or the budget is 0. The source is asked for a side at most the largest power of
  // two whose texture_room is half the budget, and that room is made before it is asked, so
  // the texture, the bytes its fetch holds for a moment and the textures kept stay within the
  // budget: under a small budget textures are drawn coarser, never over it. `uploaded` gets the
  // bytes uploaded.
  uint32_t get(uint32_t index, const TextureSource& source, uint64_t& uploaded);
  uint64_t resident_bytes() const { return resident_bytes_; }

 private:
  void evict_least_recent();

  struct Entry {
    uint32_t texture = 0;  // 0: the source had none (remembered, so it is not asked again)
    uint64_t bytes = 0;
    std::list<uint32_t>::iterator lru;
  };
  uint64_t budget_;
  uint64_t resident_bytes_ = 0;
  std::list<uint32_t> lru_;  // front = most recently used
  std::unordered_map<uint32_t, Entry> entries_;
};

// Bytes a texture of w × h texels takes with its full mipmap chain (the chain adds a third).
uint64_t texture_bytes(uint32_t width, uint32_t height);
// Bytes a side × side texture needs while it is fetched (read, decoded) and uploaded.
uint64_t texture_room(uint32_t side);

}  // namespace cellwalk::render
