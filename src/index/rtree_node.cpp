// HDoV thesis §4.1, §4.2.1 (digest §3.2, §4): an R-tree node is (MBR, ptr) entries; REVIEW keeps
// one node per disk page. The node page's byte layout (docs/format.md, "Section rtree"):
// u32 height, u32 entry count, then per entry 6 × f32 box (min, max) and u32 ref, zero padded.
#include <cmath>

#include "cellwalk/index/rtree.hpp"
#include "core/bytes.hpp"
#include "index/rtree_page.hpp"
#include "scene/scene_info_codec.hpp"

namespace cellwalk {

Aabb RTreeNode::bounds() const {
  Aabb box;
  for (const RTreeEntry& e : entries) box.extend(e.box);
  return box;
}

uint32_t rtree_page_capacity(uint32_t page_size) {
  return page_size < rtree_page::kNodeHeaderBytes ? 0
                                                  : (page_size - rtree_page::kNodeHeaderBytes) / rtree_page::kEntryBytes;
}

namespace rtree_page {

Aabb get_checked_box(ByteReader& r, const char* what) {
  const Aabb box = get_box(r);
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(box.min[a]) || !std::isfinite(box.max[a])) r.error(std::string(what) + " is not finite");
  if (box.empty()) r.error(std::string(what) + " has min > max");
  return box;
}

std::vector<uint8_t> encode_node(const RTreeNode& node, uint32_t page_size) {
  ByteWriter w;
  w.put(node.height);
  w.put(static_cast<uint32_t>(node.entries.size()));
  for (const RTreeEntry& e : node.entries) {
    put_box(w, e.box);
    w.put(e.ref);
  }
  std::vector<uint8_t> page = std::move(w.bytes());
  if (page.size() > page_size) fail("rtree", "internal: a node does not fit its page");
  page.resize(page_size, 0);
  return page;
}

}  // namespace rtree_page

RTreeNode decode_rtree_node(std::span<const uint8_t> page, const std::string& where) {
  ByteReader r(page, where);
  RTreeNode node;
  node.height = r.get<uint32_t>("node height");
  if (node.height > rtree_page::kMaxHeight) r.error("node height " + std::to_string(node.height) + " is implausible");
  const uint32_t count = r.get<uint32_t>("entry count");
  if (count > rtree_page_capacity(static_cast<uint32_t>(page.size())))
    r.error("entry count " + std::to_string(count) + " exceeds the page's capacity");
  node.entries.resize(count);
  for (RTreeEntry& e : node.entries) {
    e.box = rtree_page::get_checked_box(r, "entry box");
    e.ref = r.get<uint32_t>("entry ref");
  }
  return node;
}

}  // namespace cellwalk
