// The tree file of the k-d scene tree (docs/scene-tree.md, "Tree file"): names and record sizes
// of its sections, shared by its writer (scene_tree_build.cpp) and reader (scene_tree.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/systems/scene_tree/scene_tree.hpp"

namespace cellwalk::scene_tree_format {

// 2: internal LODs by build_aggregate_lods, its params stored as lod_*.
inline constexpr int kVersion = 2;
inline constexpr const char* kParams = "kd-params";      // JSON: version, world identity, params
inline constexpr const char* kNodes = "kd-nodes";        // u32 count, then kNodeRecordBytes each
inline constexpr const char* kLevels = "kd-levels";      // u32 count, then kLevelRecordBytes each
inline constexpr const char* kGeometry = "kd-geometry";  // encoded aggregate levels
constexpr size_t kNodeRecordBytes = 6 * 4 + 7 * 4;
constexpr size_t kLevelRecordBytes = 8 + 4 + 4;

// The node and level tables decoded from their sections' bytes and checked (indices in range,
// children after parents, each object in exactly one leaf with its world level count, levels
// inside the geometry section); lod_counts[o] is object o's level count. Throws Error naming
// `where` on damage. The reader's core, also driven by fuzz/scene_tree_fuzz.cpp.
struct Tables {
  std::vector<SceneTreeNode> nodes;
  std::vector<AggregateLevel> levels;
};
Tables read_tables(const std::vector<uint8_t>& nodes, const std::vector<uint8_t>& levels, uint64_t geometry_bytes,
                   std::span<const uint32_t> lod_counts, const std::string& where);

// XXH3-64 of the world's "objects" section and its "lods" entries less their offsets: a tree
// file belongs to one world, whatever the order of its levels on disk.
uint64_t world_identity(const World& world);
// The "kd-params" section's text: a tree file is reused only when it is byte-equal.
std::string params_json(const SceneTreeParams& params, uint64_t identity, size_t objects);

}  // namespace cellwalk::scene_tree_format
