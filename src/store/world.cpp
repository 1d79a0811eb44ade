// The world's directory: objects and their levels of detail (docs/format.md, "World file").
#include "cellwalk/store/world.hpp"

#include "cellwalk/core/error.hpp"
#include "core/bytes.hpp"
#include "scene/scene_info_codec.hpp"
#include "store/world_sections.hpp"

namespace cellwalk {

World::World(const std::string& path, WorldFile::Options options) : file_(path, options) {
  auto params = file_.read_all(world_sections::kParams);
  params_json_.assign(params.begin(), params.end());
  {
    const SectionInfo& s = file_.section(world_sections::kScene);
    auto bytes = file_.read(s, 0, s.bytes);
    ByteReader r(bytes, path + ": section scene", 0);
    info_ = decode_scene_info(r);
  }
  {
    const SectionInfo& s = file_.section(world_sections::kLods);
    auto bytes = file_.read(s, 0, s.bytes);
    ByteReader r(bytes, path + ": section lods", 0);
    if (s.bytes % world_sections::kLodRecordBytes != 0) r.error("size is not a whole number of level records");
    lods_.resize(s.bytes / world_sections::kLodRecordBytes);
    const uint64_t geometry_bytes = file_.section(world_sections::kGeometry).bytes;
    for (LodRecord& l : lods_) {
      l.offset = r.get<uint64_t>("level offset");
      l.bytes = r.get<uint32_t>("level bytes");
      l.triangles = r.get<uint32_t>("level triangles");
      l.error = r.get<float>("level error");
      r.get<uint32_t>("padding");
      if (l.offset > geometry_bytes || l.bytes > geometry_bytes - l.offset)
        r.error("level points outside the geometry section");
    }
  }
  {
    const SectionInfo& s = file_.section(world_sections::kObjects);
    auto bytes = file_.read(s, 0, s.bytes);
    ByteReader r(bytes, path + ": section objects", 0);
    if (s.bytes % world_sections::kObjectRecordBytes != 0) r.error("size is not a whole number of object records");
    objects_.resize(s.bytes / world_sections::kObjectRecordBytes);
    for (ObjectRecord& o : objects_) {
      o.bounds = get_box(r);
      o.color = r.get<uint32_t>("colour");
      o.lod_count = r.get<uint32_t>("level count");
      o.first_lod = r.get<uint64_t>("first level");
      if (o.lod_count == 0 || o.first_lod > lods_.size() || o.lod_count > lods_.size() - o.first_lod)
        r.error("object's levels lie outside the level table");
    }
  }
  if (file_.has_section(world_sections::kTextureTable)) {
    const SectionInfo& s = file_.section(world_sections::kTextureTable);
    auto bytes = file_.read(s, 0, s.bytes);
    ByteReader r(bytes, path + ": section texture_table", 0);
    if (s.bytes % world_sections::kTextureRecordBytes != 0) r.error("size is not a whole number of texture records");
    const uint64_t image_bytes = file_.section(world_sections::kTextures).bytes;
    textures_.resize(s.bytes / world_sections::kTextureRecordBytes);
    for (auto& [offset, size] : textures_) {
      offset = r.get<uint64_t>("texture offset");
      size = r.get<uint32_t>("texture bytes");
      r.get<uint32_t>("padding");
      if (size == 0 || offset > image_bytes || size > image_bytes - offset)
        r.error("texture points outside the textures section");
    }
  }
}

const LodRecord& World::lod(ObjectId id, uint32_t level) const {
  const ObjectRecord& o = objects_.at(id);
  if (level >= o.lod_count)
    fail(file_.path(), "object " + std::to_string(id) + " has " + std::to_string(o.lod_count) +
                           " levels, level " + std::to_string(level) + " was asked for");
  return lods_[o.first_lod + level];
}

uint64_t World::triangle_count() const {
  uint64_t n = 0;
  for (const ObjectRecord& o : objects_) n += lods_[o.first_lod].triangles;
  return n;
}

std::vector<uint8_t> World::read_level(ObjectId id, uint32_t level) const {
  const LodRecord& l = lod(id, level);
  return file_.read(file_.section(world_sections::kGeometry), l.offset, l.bytes);
}

Mesh World::decode_level(ObjectId id, uint32_t level, std::span<const uint8_t> bytes) const {
  const LodRecord& l = lod(id, level);
  Mesh mesh = decode_mesh(bytes, file_.path() + ": object " + std::to_string(id) + " level " + std::to_string(level));
  if (mesh.triangle_count() != l.triangles)
    fail(file_.path() + ": object " + std::to_string(id) + " level " + std::to_string(level),
         "decoded " + std::to_string(mesh.triangle_count()) + " triangles, the directory says " +
             std::to_string(l.triangles));
  if (mesh.texture != kNoTexture && mesh.texture >= textures_.size())
    fail(file_.path() + ": object " + std::to_string(id) + " level " + std::to_string(level),
         "samples texture " + std::to_string(mesh.texture) + ", but the world has " +
             std::to_string(textures_.size()) + " (the file is damaged: rebuild it)");
  return mesh;
}

std::vector<uint8_t> World::read_texture(uint32_t index) const {
  if (index >= textures_.size())
    fail(file_.path(), "texture " + std::to_string(index) + " does not exist (the world has " +
                           std::to_string(textures_.size()) + ")");
  const auto [offset, size] = textures_[index];
  return file_.read(file_.section(world_sections::kTextures), offset, size);
}

Texture World::load_texture(uint32_t index, uint32_t max_side) const {
  return decode_texture(read_texture(index), file_.path() + ": texture " + std::to_string(index), max_side);
}

std::vector<std::string> World::object_names() const {
  std::vector<std::string> names(objects_.size());
  if (!file_.has_section(world_sections::kNames)) return names;
  const std::vector<uint8_t> bytes = file_.read_all(world_sections::kNames);
  ByteReader r(bytes, file_.path() + ": section names", 0);
  for (std::string& name : names) name = r.get_string("object name");
  if (r.remaining() != 0) r.error("holds more names than the world has objects");
  return names;
}

uint64_t World::resident_bytes() const {
  return objects_.capacity() * sizeof(ObjectRecord) + lods_.capacity() * sizeof(LodRecord) +
         textures_.capacity() * sizeof(textures_[0]) +
         file_.resident_bytes() + info_.nav.nodes.size() * sizeof(Vec3) + info_.nav.edges.size() * 8;
}

}  // namespace cellwalk
