// Base-colour textures as GL textures, mipmapped, repeating (glTF's default sampler).
#include "render/mesh_textures.hpp"

#include <epoxy/gl.h>

#include <algorithm>
#include <bit>

namespace cellwalk::render {

uint64_t texture_bytes(uint32_t width, uint32_t height) {
  return uint64_t(width) * height * 4 * 4 / 3;
}

uint64_t texture_room(uint32_t side) {
  // While a texture is fetched and uploaded: its encoded level and its decoded texels (each at
  // most w × h × 4) beside the GL storage being filled.
  return texture_bytes(side, side) + 2 * uint64_t(side) * side * 4;
}

namespace {

// The largest power-of-two side whose square texture needs at most `bytes` of room.
uint32_t max_side_within(uint64_t bytes) {
  uint32_t side = 1;
  while (side < (1u << 15) && texture_room(side * 2) <= bytes) side *= 2;
  return side;
}

GLuint upload(const Texture& t) {
  const int levels = std::bit_width(std::max(t.width, t.height));
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &texture);
  glTextureStorage2D(texture, levels, GL_RGBA8, GLsizei(t.width), GLsizei(t.height));
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTextureSubImage2D(texture, 0, 0, 0, GLsizei(t.width), GLsizei(t.height), GL_RGBA, GL_UNSIGNED_BYTE,
                      t.texels.data());
  glGenerateTextureMipmap(texture);
  glTextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTextureParameteri(texture, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_T, GL_REPEAT);
  return texture;
}

}  // namespace

MeshTextures::~MeshTextures() {
  for (const auto& [index, entry] : entries_)
    if (entry.texture) glDeleteTextures(1, &entry.texture);
}

uint32_t MeshTextures::get(uint32_t index, const TextureSource& source, uint64_t& uploaded) {
  if (auto it = entries_.find(index); it != entries_.end()) {
    lru_.splice(lru_.begin(), lru_, it->second.lru);
    return it->second.texture;
  }
  if (!source || budget_ == 0) return 0;
  const uint32_t max_side = max_side_within(budget_ / 2);
  // Room first, so the fetch's transient bytes are within the budget too.
  while (resident_bytes_ + texture_room(max_side) > budget_ && !lru_.empty()) evict_least_recent();
  const std::optional<Texture> t = source(index, max_side);
  Entry entry;
  if (t && t->width > 0 && t->height > 0 && t->width <= max_side && t->height <= max_side &&
      t->texels.size() == size_t(t->width) * t->height) {
    entry.bytes = texture_bytes(t->width, t->height);
    entry.texture = upload(*t);
    uploaded += entry.bytes;
    resident_bytes_ += entry.bytes;
  }
  lru_.push_front(index);
  entry.lru = lru_.begin();
  return entries_.emplace(index, entry).first->second.texture;
}

void MeshTextures::evict_least_recent() {
  const uint32_t index = lru_.back();
  lru_.pop_back();
  const auto it = entries_.find(index);
  resident_bytes_ -= it->second.bytes;
  if (it->second.texture) glDeleteTextures(1, &it->second.texture);
  entries_.erase(it);
}

}  // namespace cellwalk::render
