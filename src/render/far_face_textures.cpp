// Stratified thesis §3.1.2, §3.2 (digest 002 §3.6, §3.8): far-face images as GL textures.
#include "render/far_face_textures.hpp"

#include <epoxy/gl.h>

#include <string>

#include "cellwalk/core/error.hpp"

namespace cellwalk::render {
namespace {

GLuint make_texture(GLenum format, int width, int height, GLenum filter) {
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &texture);
  glTextureStorage2D(texture, 1, format, width, height);
  glTextureParameteri(texture, GL_TEXTURE_MIN_FILTER, filter);
  glTextureParameteri(texture, GL_TEXTURE_MAG_FILTER, filter);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return texture;
}

void delete_textures(const FaceTextures& t) {
  const GLuint names[] = {t.color, t.ids};
  glDeleteTextures(t.ids ? 2 : 1, names);
}

}  // namespace

FarFaceTextures::~FarFaceTextures() {
  for (const auto& [id, entry] : entries_) delete_textures(entry.textures);
}

const FaceTextures& FarFaceTextures::get(const FarFace& face, uint64_t& uploaded) {
  if (auto it = entries_.find(face.id); it != entries_.end()) {
    lru_.splice(lru_.begin(), lru_, it->second.lru);
    return it->second.textures;
  }
  const Image* color = face.color;
  const std::string where = "far face " + std::to_string(face.id);
  if (!color || color->width <= 0 || color->height <= 0 || color->rgba.size() != size_t(color->width) * color->height * 4)
    fail(where, "has no colour image or one whose size does not match its pixels");
  if (face.ids && (face.ids->width != color->width || face.ids->height != color->height ||
                   face.ids->ids.size() != size_t(color->width) * color->height))
    fail(where, "has an id image of another size than its colour image");
  const uint64_t bytes = uint64_t(color->width) * color->height * (face.ids ? 8 : 4);
  if (bytes > budget_)
    fail(where, "needs " + std::to_string(bytes) + " bytes of textures, more than the far-face budget of " +
                    std::to_string(budget_) + "; raise RenderSettings::far_face_budget_bytes");
  while (resident_bytes_ + bytes > budget_) evict_least_recent();
  FaceTextures t;
  t.bytes = bytes;
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  t.color = make_texture(GL_RGBA8, color->width, color->height, GL_LINEAR);
  glTextureSubImage2D(t.color, 0, 0, 0, color->width, color->height, GL_RGBA, GL_UNSIGNED_BYTE, color->rgba.data());
  if (face.ids) {
    t.ids = make_texture(GL_R32UI, color->width, color->height, GL_NEAREST);
    glTextureSubImage2D(t.ids, 0, 0, 0, color->width, color->height, GL_RED_INTEGER, GL_UNSIGNED_INT, face.ids->ids.data());
  }
  uploaded += bytes;
  resident_bytes_ += bytes;
  lru_.push_front(face.id);
  return entries_.emplace(face.id, Entry{t, lru_.begin()}).first->second.textures;
}

void FarFaceTextures::evict_least_recent() {
  const uint32_t id = lru_.back();
  lru_.pop_back();
  const auto it = entries_.find(id);
  resident_bytes_ -= it->second.textures.bytes;
  delete_textures(it->second.textures);
  entries_.erase(it);
}

}  // namespace cellwalk::render
