// Names and record sizes of the world file's sections (docs/format.md, "World file").
#pragma once

#include <cstddef>

namespace cellwalk::world_sections {

inline constexpr const char* kParams = "params";      // build parameters, JSON
inline constexpr const char* kScene = "scene";        // SceneInfo: generator, bounds, navigation
inline constexpr const char* kObjects = "objects";    // one ObjectRecord per object
inline constexpr const char* kLods = "lods";          // one LodRecord per level
inline constexpr const char* kGeometry = "geometry";  // encoded levels (mesh_codec)
inline constexpr const char* kNames = "names";        // object names, in id order (optional)
inline constexpr const char* kTextureTable = "texture_table";  // textures and their levels (optional)
inline constexpr const char* kTextures = "textures";  // the levels' image files (PNG, JPEG)

constexpr size_t kObjectRecordBytes = 24 + 4 + 4 + 8;
constexpr size_t kLodRecordBytes = 8 + 4 + 4 + 4 + 4;
constexpr size_t kTextureRecordBytes = 4 + 4;                 // first level, level count
constexpr size_t kTextureLevelRecordBytes = 8 + 4 + 4 + 4 + 4;  // offset in kTextures, bytes, width, height, zero

}  // namespace cellwalk::world_sections
