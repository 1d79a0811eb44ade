// The tree file of the k-d scene tree (docs/hdov-tree.md, "Tree file"): names and record sizes
// of its sections, shared by its writer (kd_scene_tree_build.cpp) and reader (kd_scene_tree.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "cellwalk/hdov_scene_tree.hpp"

namespace cellwalk::kd_format {

// 2: internal LODs by build_aggregate_lods, its params stored as lod_*.
inline constexpr int kVersion = 2;
inline constexpr const char* kParams = "kd-params";      // JSON: version, world identity, params
inline constexpr const char* kNodes = "kd-nodes";        // u32 count, then kNodeRecordBytes each
inline constexpr const char* kLevels = "kd-levels";      // u32 count, then kLevelRecordBytes each
inline constexpr const char* kGeometry = "kd-geometry";  // encoded aggregate levels
constexpr size_t kNodeRecordBytes = 6 * 4 + 7 * 4;
constexpr size_t kLevelRecordBytes = 8 + 4 + 4;

// XXH3-64 of the world's "objects" and "lods" sections: a tree file belongs to one world.
uint64_t world_identity(const World& world);
// The "kd-params" section's text: a tree file is reused only when it is byte-equal.
std::string params_json(const KdSceneTreeParams& params, uint64_t identity, size_t objects);

}  // namespace cellwalk::kd_format
