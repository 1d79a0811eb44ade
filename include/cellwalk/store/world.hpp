// A built world: the scene's objects as LOD chains in a world file, with the directory that
// says where each level lies, how many triangles it has and how far it may be from the
// original (its object-space error). `cellwalk build` makes it from a scene file.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/lod/lod.hpp"
#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/store/mesh_codec.hpp"
#include "cellwalk/scene/scene.hpp"
#include "cellwalk/scene/texture.hpp"
#include "cellwalk/store/world_file.hpp"

namespace cellwalk {

struct BuildParams {
  uint32_t page_size = kDefaultPageSize;
  LodParams lod;
  CodecParams codec;
  int threads = 0;  // 0 = all cores
};

struct BuildReport {
  uint64_t objects = 0;
  uint64_t triangles = 0;         // of the scene (level 0)
  uint64_t stored_triangles = 0;  // all levels
  uint64_t levels = 0;
  uint64_t raw_bytes = 0;         // level 0 as float positions + normals + u32 indices
  uint64_t geometry_bytes = 0;    // all levels, encoded
  uint64_t level0_bytes = 0;      // level 0, encoded
  uint64_t file_bytes = 0;
  double seconds = 0.0;
  uint64_t peak_rss_bytes = 0;    // of the process, from /proc/self/status VmHWM
};

// Sections a layer above the store adds to a world as it is built (e.g. the R-tree of
// src/index), given the objects' boxes in id order; called after the directory is written.
using ExtraSections = std::function<void(WorldWriter& writer, std::span<const Aabb> object_bounds)>;

// Streams `scene_file` into a new world file at `world_file`, objects in parallel, a bounded
// number at a time. Called with (objects done, objects total).
BuildReport build_world(const std::string& scene_file, const std::string& world_file,
                        const BuildParams& params,
                        const std::function<void(uint64_t, uint64_t)>& progress = {},
                        const ExtraSections& extra_sections = {});

// One object's entry in the directory.
struct ObjectRecord {
  Aabb bounds;
  Rgba8 color = 0;
  uint32_t lod_count = 0;
  uint64_t first_lod = 0;  // index of its level 0 in the level table
};

// One level of detail's entry.
struct LodRecord {
  uint64_t offset = 0;  // in the geometry section
  uint32_t bytes = 0;
  uint32_t triangles = 0;
  float error = 0.0f;   // object-space, metres
};

// Opens a world file and holds its directory (objects and levels) in memory.
// Thread-safety: const methods may be called concurrently.
class World {
 public:
  World(const std::string& path, WorldFile::Options options = {});

  const WorldFile& file() const { return file_; }
  const SceneInfo& info() const { return info_; }
  const std::string& build_params_json() const { return params_json_; }
  size_t object_count() const { return objects_.size(); }
  const ObjectRecord& object(ObjectId id) const { return objects_.at(id); }
  const LodRecord& lod(ObjectId id, uint32_t level) const;
  uint64_t triangle_count() const;  // level 0 of every object

  // The encoded bytes of one level (verified pages), and their decoding.
  std::vector<uint8_t> read_level(ObjectId id, uint32_t level) const;
  Mesh decode_level(ObjectId id, uint32_t level, std::span<const uint8_t> bytes) const;

  // Base-colour textures: how many the world has, and one's image file as imported (PNG or
  // JPEG, verified pages). Meshes name them by index (Mesh::texture).
  size_t texture_count() const { return textures_.size(); }
  std::vector<uint8_t> read_texture(uint32_t index) const;
  // Texture `index` decoded from the largest of its levels (texture_levels) whose sides are at
  // most max_side: only that level's bytes are read and decoded.
  Texture load_texture(uint32_t index, uint32_t max_side) const;

  // The objects' names, in id order, read from the file on each call (the directory does not
  // hold them: a budgeted run never needs them). Empty names for a world built without them.
  std::vector<std::string> object_names() const;
  // Memory the open world holds: directory, checksum and section tables.
  uint64_t resident_bytes() const;

 private:
  WorldFile file_;
  SceneInfo info_;
  std::string params_json_;
  std::vector<ObjectRecord> objects_;
  std::vector<LodRecord> lods_;
  void read_texture_table();
  void check_texture_index(uint32_t index) const;
  struct TextureLevelRecord {
    uint64_t offset = 0;  // in the textures section
    uint32_t bytes = 0, width = 0, height = 0;
  };
  std::vector<std::pair<uint32_t, uint32_t>> textures_;  // first level, level count
  std::vector<TextureLevelRecord> texture_levels_;
};

}  // namespace cellwalk
