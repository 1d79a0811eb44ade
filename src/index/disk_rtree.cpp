// Reading REVIEW's R-tree from the world file (HDoV thesis §4.2.1, digest §3.2, §8.1 "exact
// logical page-I/O counters"): the header page once, then exactly one verified page per node.
#include <deque>

#include "cellwalk/core/error.hpp"
#include "cellwalk/index/rtree.hpp"
#include "cellwalk/store/world.hpp"
#include "index/rtree_page.hpp"
#include "scene/scene_info_codec.hpp"

namespace cellwalk {

DiskRTree::DiskRTree(const World& world) : name_(world.file().path() + " section rtree") {
  if (!world.file().has_section(kRTreeSection))
    fail(world.file().path(), "has no R-tree (section rtree); rebuild it with `cellwalk build` of this version");
  const WorldFile& file = world.file();
  const SectionInfo& section = file.section(kRTreeSection);
  read_ = [&file, section](uint64_t offset, uint64_t length) { return file.read(section, offset, length); };
  parse_header(read_(0, std::min<uint64_t>(section.bytes, file.page_size())));
  if (page_size_ != file.page_size()) fail(name_, "page size differs from the world file's");
  if ((node_count_ + 1) * page_size_ != section.bytes) fail(name_, "section length does not match its node count");
  if (object_count_ != world.object_count()) fail(name_, "indexes a different number of objects than the world holds");
}

DiskRTree::DiskRTree(std::vector<uint8_t> section, std::string name) : name_(std::move(name)) {
  auto bytes = std::make_shared<const std::vector<uint8_t>>(std::move(section));
  read_ = [bytes, name = name_](uint64_t offset, uint64_t length) {
    if (offset > bytes->size() || length > bytes->size() - offset)
      fail(name + "@" + std::to_string(offset), "read past the end of the section");
    return std::vector<uint8_t>(bytes->begin() + std::ptrdiff_t(offset), bytes->begin() + std::ptrdiff_t(offset + length));
  };
  parse_header(read_(0, std::min<uint64_t>(bytes->size(), rtree_page::kHeaderBytes)));
  if (bytes->size() / page_size_ < node_count_ + 1) fail(name_, "section is shorter than its node count");
}

void DiskRTree::parse_header(std::span<const uint8_t> bytes) {
  ByteReader r(bytes, name_);
  if (r.get<uint32_t>("version") != rtree_page::kVersion) r.error("unknown R-tree version");
  page_size_ = r.get<uint32_t>("page size");
  max_entries_ = r.get<uint32_t>("max entries");
  min_entries_ = r.get<uint32_t>("min entries");
  height_ = r.get<uint32_t>("height");
  const uint32_t root = r.get<uint32_t>("root");
  node_count_ = r.get<uint64_t>("node count");
  object_count_ = r.get<uint64_t>("object count");
  const uint32_t method = r.get<uint32_t>("method");
  r.get<uint32_t>("reserved");
  bounds_ = rtree_page::get_checked_box(r, "bounds");
  if (page_size_ < 512 || (page_size_ & (page_size_ - 1)) != 0) r.error("page size is not a power of two >= 512");
  if (max_entries_ < 4 || max_entries_ > rtree_page_capacity(page_size_) || min_entries_ < 1 ||
      min_entries_ > max_entries_ / 2)
    r.error("fan-out M/m out of range");
  if (height_ < 1 || height_ > rtree_page::kMaxHeight || root != 0 || node_count_ < 1 || node_count_ > UINT32_MAX)
    r.error("height, root or node count out of range");
  if (method > uint32_t(RTreeMethod::kStr)) r.error("unknown build method");
  if (object_count_ > UINT32_MAX || object_count_ > node_count_ * max_entries_) r.error("object count out of range");
  method_ = static_cast<RTreeMethod>(method);
}

RTreeNode DiskRTree::read_node(uint32_t index, uint32_t height) const {
  const std::string where = name_ + " node " + std::to_string(index);
  if (index >= node_count_) fail(where, "node index out of range (the tree is damaged)");
  RTreeNode node = decode_rtree_node(read_(uint64_t(index + 1) * page_size_, page_size_), where);
  if (node.height != height) fail(where, "height " + std::to_string(node.height) + ", expected " + std::to_string(height));
  if (node.entries.size() > max_entries_) fail(where, "holds more than M entries");
  for (const RTreeEntry& e : node.entries)
    if ((node.leaf() && e.ref >= object_count_) || (!node.leaf() && (e.ref <= index || e.ref >= node_count_)))
      fail(where, "entry points outside the tree (ref " + std::to_string(e.ref) + ")");
  return node;
}

uint64_t DiskRTree::check() const {
  std::vector<bool> seen(object_count_, false), reached(node_count_, false);
  uint64_t visited = 0, objects = 0;
  struct Pending {
    uint32_t index, height;
    Aabb box;  // the parent entry's box; empty for the root
  };
  std::deque<Pending> queue{{0, height_ - 1, Aabb{}}};
  while (!queue.empty()) {
    const Pending p = queue.front();
    queue.pop_front();
    const RTreeNode node = read_node(p.index, p.height);
    ++visited;
    const std::string where = name_ + " node " + std::to_string(p.index);
    const Aabb b = node.bounds();
    if (!p.box.empty() && (b.min != p.box.min || b.max != p.box.max))
      fail(where, "its parent's entry box is not its bounds");
    if (node.entries.empty() && (p.index != 0 || object_count_ != 0)) fail(where, "is empty");
    for (const RTreeEntry& e : node.entries) {
      if (!node.leaf()) {
        if (reached[e.ref]) fail(where, "shares child node " + std::to_string(e.ref) + " with another entry");
        reached[e.ref] = true;
        queue.push_back({e.ref, node.height - 1, e.box});
        continue;
      }
      if (seen[e.ref]) fail(where, "object " + std::to_string(e.ref) + " is indexed twice");
      seen[e.ref] = true;
      ++objects;
    }
  }
  if (objects != object_count_) fail(name_, "indexes " + std::to_string(objects) + " of " + std::to_string(object_count_) + " objects");
  if (visited != node_count_) fail(name_, "holds " + std::to_string(node_count_ - visited) + " unreachable nodes");
  return visited;
}

}  // namespace cellwalk
