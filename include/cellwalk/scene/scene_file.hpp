// The scene file (.cwscene): the streamed output of generators and importers and the input of
// `cellwalk build`. Objects are written one record at a time, each with its own checksum; a
// footer holds the table of contents and the SceneInfo. Layout in docs/format.md.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <span>
#include <vector>

#include "cellwalk/scene/scene.hpp"

namespace cellwalk {

// Writes a scene file. Records go to a temporary file; finish() writes the footer, fsyncs and
// renames, so an interrupted write never leaves a file at `path` that looks valid, and an
// existing file at `path` survives any failure. Memory: 44 bytes per object for the table.
class SceneWriter : public ObjectSink {
 public:
  explicit SceneWriter(std::string path);
  ~SceneWriter() override;  // removes the temporary file if finish() was not reached
  // REQUIRES: object.id == number of objects added before (ids are dense).
  // REQUIRES: object.mesh.texture is kNoTexture or a texture added before.
  void add(const Object& object) override;
  // Keeps the image's bytes as they are; checks that it is a PNG or JPEG (check_texture).
  void add_texture(const TextureImage& texture) override;
  // `info.bounds` is replaced by the union of the objects' bounds.
  void finish(SceneInfo info);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One row of the table of contents.
struct SceneEntry {
  uint64_t offset = 0;  // of the record
  uint32_t size = 0;    // record bytes
  uint32_t triangles = 0;
  Rgba8 color = 0;
  Aabb bounds;
};

// Reads a scene file. Opening checks the trailer and footer; each object's record is checked
// when read. Damage gives one Error naming the file, the part and the byte offset.
// Thread-safety: read_object() may be called concurrently (it uses pread).
class SceneReader {
 public:
  explicit SceneReader(std::string path);
  ~SceneReader();

  const std::string& path() const { return path_; }
  const SceneInfo& info() const { return info_; }
  size_t object_count() const { return entries_.size(); }
  const SceneEntry& entry(ObjectId id) const { return entries_.at(id); }
  uint64_t triangle_count() const { return triangles_; }
  Object read_object(ObjectId id) const;
  size_t texture_count() const { return textures_.size(); }
  TextureImage read_texture(uint32_t index) const;
  // The two halves of read_object, so callers can time I/O and decoding apart.
  std::vector<uint8_t> read_record(ObjectId id) const;
  Object decode_record(ObjectId id, std::span<const uint8_t> record) const;
  // Bytes read from the file so far by read_object (exact, for the I/O counters).
  uint64_t bytes_read() const { return bytes_read_.load(); }

 private:
  std::string path_;
  int fd_ = -1;
  SceneInfo info_;
  std::vector<SceneEntry> entries_;
  std::vector<std::pair<uint64_t, uint32_t>> textures_;  // record offset and size
  uint64_t triangles_ = 0;
  mutable std::atomic<uint64_t> bytes_read_{0};
};

}  // namespace cellwalk
