// The byte layout shared by the R-tree's writer and reader (docs/format.md, "Section rtree").
#pragma once

#include <cstdint>
#include <vector>

#include "cellwalk/index/rtree.hpp"
#include "core/bytes.hpp"

namespace cellwalk::rtree_page {

constexpr uint32_t kVersion = 1;
constexpr uint32_t kNodeHeaderBytes = 8;   // u32 height, u32 count
constexpr uint32_t kEntryBytes = 28;       // 6 × f32 box, u32 ref
constexpr uint32_t kHeaderBytes = 72;      // the section's first page, before its padding
constexpr uint32_t kMaxHeight = 64;

// Reads a box (scene_info_codec's form) and checks it is finite with min <= max.
Aabb get_checked_box(ByteReader& r, const char* what);
// One page: the node's bytes zero-padded to `page_size`.
std::vector<uint8_t> encode_node(const RTreeNode& node, uint32_t page_size);

}  // namespace cellwalk::rtree_page
