// The GL textures of far faces (stratified rendering), keyed by face id and kept under a byte
// budget with least-recently-used eviction, like the mesh cache beside it.
#pragma once

#include <cstdint>
#include <list>
#include <unordered_map>

#include "cellwalk/render/renderer.hpp"

namespace cellwalk::render {

struct FaceTextures {
  uint32_t color = 0;  // RGBA8, linear filtering
  uint32_t ids = 0;    // R32UI, or 0 when the face has no id image
  uint64_t bytes = 0;
};

// REQUIRES: a current GL context for the lifetime of the object. Deleting a texture a queued draw
// still reads is safe in GL (its storage lives until the draw completes, OpenGL 4.5 §5.1.3).
class FarFaceTextures {
 public:
  explicit FarFaceTextures(uint64_t budget_bytes) : budget_(budget_bytes) {}
  ~FarFaceTextures();
  FarFaceTextures(const FarFaceTextures&) = delete;
  FarFaceTextures& operator=(const FarFaceTextures&) = delete;

  // The textures of `face`, uploaded (evicting the least recently used) when not resident;
  // `uploaded` gets the bytes uploaded. Throws Error for an image of the wrong size or one
  // larger than the whole budget.
  const FaceTextures& get(const FarFace& face, uint64_t& uploaded);
  uint64_t resident_bytes() const { return resident_bytes_; }

 private:
  void evict_least_recent();

  struct Entry {
    FaceTextures textures;
    std::list<uint32_t>::iterator lru;
  };
  uint64_t budget_;
  uint64_t resident_bytes_ = 0;
  std::list<uint32_t> lru_;  // front = most recently used
  std::unordered_map<uint32_t, Entry> entries_;
};

}  // namespace cellwalk::render
