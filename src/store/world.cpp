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
  if (file_.has_section(world_sections::kTextureTable)) read_texture_table();
}

void World::read_texture_table() {
  const SectionInfo& s = file_.section(world_sections::kTextureTable);
  auto bytes = file_.read(s, 0, s.bytes);
  ByteReader r(bytes, file_.path() + ": section texture_table", 0);
  const uint32_t count = r.get<uint32_t>("texture count"), level_count = r.get<uint32_t>("level count");
  if (uint64_t(count) * world_sections::kTextureRecordBytes +
          uint64_t(level_count) * world_sections::kTextureLevelRecordBytes != r.remaining())
    r.error("size does not match its texture and level counts");
  textures_.resize(count);
  for (auto& [first, n] : textures_) {
    first = r.get<uint32_t>("first level");
    n = r.get<uint32_t>("level count");
    if (n == 0 || first > level_count || n > level_count - first) r.error("texture's levels lie outside the level table");
  }
  const uint64_t image_bytes = file_.section(world_sections::kTextures).bytes;
  texture_levels_.resize(level_count);
  for (TextureLevelRecord& l : texture_levels_) {
    l.offset = r.get<uint64_t>("level offset");
    l.bytes = r.get<uint32_t>("level bytes");
    l.width = r.get<uint32_t>("level width");
    l.height = r.get<uint32_t>("level height");
    r.get<uint32_t>("padding");
    if (l.bytes == 0 || l.offset > image_bytes || l.bytes > image_bytes - l.offset)
      r.error("texture level points outside the textures section");
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

void World::check_texture_index(uint32_t index) const {
  if (index >= textures_.size())
    fail(file_.path(), "texture " + std::to_string(index) + " does not exist (the world has " +
                           std::to_string(textures_.size()) + ")");
}

std::vector<uint8_t> World::read_texture(uint32_t index) const {
  check_texture_index(index);
  const TextureLevelRecord& l = texture_levels_[textures_[index].first];
  return file_.read(file_.section(world_sections::kTextures), l.offset, l.bytes);
}

Texture World::load_texture(uint32_t index, uint32_t max_side) const {
  check_texture_index(index);
  const auto [first, n] = textures_[index];
  uint32_t chosen = first + n - 1;  // the 1 × 1 level when none is smaller than asked
  for (uint32_t l = first; l < first + n; ++l)
    if (texture_levels_[l].width <= max_side && texture_levels_[l].height <= max_side) {
      chosen = l;
      break;
    }
  const TextureLevelRecord& level = texture_levels_[chosen];
  const std::string where = file_.path() + ": texture " + std::to_string(index) + " level " + std::to_string(chosen - first);
  Texture t = decode_texture(file_.read(file_.section(world_sections::kTextures), level.offset, level.bytes), where,
                             std::max(level.width, level.height));
  if (t.width != level.width || t.height != level.height)
    fail(where, "decodes to " + std::to_string(t.width) + " x " + std::to_string(t.height) + ", the table says " +
                    std::to_string(level.width) + " x " + std::to_string(level.height) + " (the file is damaged: rebuild it)");
  return t;
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
         textures_.capacity() * sizeof(textures_[0]) + texture_levels_.capacity() * sizeof(TextureLevelRecord) +
         file_.resident_bytes() + info_.nav.nodes.size() * sizeof(Vec3) + info_.nav.edges.size() * 8;
}

}  // namespace cellwalk
