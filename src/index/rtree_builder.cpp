// Building REVIEW's R-tree (HDoV thesis §4.2.1, digest §3.2): Guttman's insertion (ChooseLeaf by
// least volume enlargement, AdjustTree, split on overflow) with Ang & Tan's linear split; or
// Sort-Tile-Recursive packing (Leutenegger, Lopez, Edgington, ICDE 1997) as an option. Nodes
// are numbered breadth first and written one per page (docs/format.md, "Section rtree").
#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>

#include "cellwalk/core/error.hpp"
#include "cellwalk/index/rtree.hpp"
#include "cellwalk/store/world.hpp"
#include "index/linear_split.hpp"
#include "index/rtree_page.hpp"
#include "scene/scene_info_codec.hpp"

namespace cellwalk {
namespace {

double volume(const Aabb& box) {
  const Vec3 s = box.size();
  return double(s.x) * double(s.y) * double(s.z);
}

Aabb united(Aabb a, const Aabb& b) {
  a.extend(b);
  return a;
}

// Guttman's insertion; `nodes` holds the tree with arbitrary indices, `root` its root.
class InsertionBuilder {
 public:
  InsertionBuilder(uint32_t max_entries, uint32_t min_entries) : max_(max_entries), min_(min_entries) {
    nodes_.push_back(RTreeNode{});
  }

  void insert(const RTreeEntry& entry) {
    if (std::optional<uint32_t> sibling = insert_into(root_, entry)) {
      RTreeNode root;
      root.height = nodes_[root_].height + 1;
      root.entries = {{nodes_[root_].bounds(), root_}, {nodes_[*sibling].bounds(), *sibling}};
      nodes_.push_back(std::move(root));
      root_ = static_cast<uint32_t>(nodes_.size() - 1);
    }
  }
  std::vector<RTreeNode>& nodes() { return nodes_; }
  uint32_t root() const { return root_; }

 private:
  // ChooseSubtree: least enlargement of volume, then least volume.
  size_t choose(const RTreeNode& node, const Aabb& box) const {
    size_t best = 0;
    double best_growth = 0, best_volume = 0;
    for (size_t i = 0; i < node.entries.size(); ++i) {
      const double v = volume(node.entries[i].box);
      const double growth = volume(united(node.entries[i].box, box)) - v;
      if (i == 0 || growth < best_growth || (growth == best_growth && v < best_volume)) {
        best = i;
        best_growth = growth;
        best_volume = v;
      }
    }
    return best;
  }

  // Inserts below node `n`; returns the new sibling if `n` split. References into nodes_ are
  // not held across the recursion (it may grow the vector).
  std::optional<uint32_t> insert_into(uint32_t n, const RTreeEntry& entry) {
    if (nodes_[n].leaf()) {
      nodes_[n].entries.push_back(entry);
    } else {
      const size_t slot = choose(nodes_[n], entry.box);
      const uint32_t child = nodes_[n].entries[slot].ref;
      const std::optional<uint32_t> sibling = insert_into(child, entry);
      nodes_[n].entries[slot].box = nodes_[child].bounds();
      if (sibling) nodes_[n].entries.push_back({nodes_[*sibling].bounds(), *sibling});
    }
    if (nodes_[n].entries.size() <= max_) return std::nullopt;
    auto [low, high] = linear_split(std::move(nodes_[n].entries), min_);
    nodes_[n].entries = std::move(low);
    RTreeNode sibling;
    sibling.height = nodes_[n].height;
    sibling.entries = std::move(high);
    nodes_.push_back(std::move(sibling));
    return static_cast<uint32_t>(nodes_.size() - 1);
  }

  uint32_t max_, min_;
  std::vector<RTreeNode> nodes_;
  uint32_t root_ = 0;
};

Vec3 centre(const RTreeEntry& e) { return e.box.center(); }

// Sort-Tile-Recursive: groups of at most M entries, tiled in x, then y, then z.
std::vector<std::vector<RTreeEntry>> str_tiles(std::vector<RTreeEntry> entries, uint32_t max_entries) {
  const size_t n = entries.size();
  const size_t pages = (n + max_entries - 1) / max_entries;
  const size_t s = std::max<size_t>(1, size_t(std::ceil(std::cbrt(double(pages)))));
  auto by = [](int axis) {
    return [axis](const RTreeEntry& a, const RTreeEntry& b) { return centre(a)[axis] < centre(b)[axis]; };
  };
  std::vector<std::vector<RTreeEntry>> tiles;
  const size_t slab = s * s * max_entries, row = s * max_entries;
  std::sort(entries.begin(), entries.end(), by(0));
  for (size_t x = 0; x < n; x += slab) {
    const auto x_end = entries.begin() + std::ptrdiff_t(std::min(n, x + slab));
    std::sort(entries.begin() + std::ptrdiff_t(x), x_end, by(1));
    for (size_t y = x; y < size_t(x_end - entries.begin()); y += row) {
      const auto y_end = entries.begin() + std::ptrdiff_t(std::min<size_t>(x_end - entries.begin(), y + row));
      std::sort(entries.begin() + std::ptrdiff_t(y), y_end, by(2));
      for (auto it = entries.begin() + std::ptrdiff_t(y); it < y_end;) {
        const auto end = it + std::min<std::ptrdiff_t>(max_entries, y_end - it);
        tiles.emplace_back(it, end);
        it = end;
      }
    }
  }
  return tiles;
}

// Packs levels bottom-up until one node remains; returns (nodes, root).
std::pair<std::vector<RTreeNode>, uint32_t> str_pack(std::vector<RTreeEntry> entries, uint32_t max_entries) {
  std::vector<RTreeNode> nodes;
  uint32_t height = 0;
  while (true) {
    std::vector<RTreeEntry> parents;
    for (std::vector<RTreeEntry>& tile : str_tiles(std::move(entries), max_entries)) {
      RTreeNode node;
      node.height = height;
      node.entries = std::move(tile);
      parents.push_back({node.bounds(), static_cast<uint32_t>(nodes.size())});
      nodes.push_back(std::move(node));
    }
    if (parents.size() <= 1) return {std::move(nodes), static_cast<uint32_t>(nodes.size() - 1)};
    entries = std::move(parents);
    ++height;
  }
}

// Renumbers breadth first from `root` (root = 0, each level after the one above it).
std::vector<RTreeNode> breadth_first(std::vector<RTreeNode>& nodes, uint32_t root) {
  std::vector<RTreeNode> out;
  std::deque<uint32_t> queue{root};
  while (!queue.empty()) {
    RTreeNode node = std::move(nodes[queue.front()]);
    queue.pop_front();
    if (!node.leaf())
      for (RTreeEntry& e : node.entries) {
        queue.push_back(e.ref);
        e.ref = static_cast<uint32_t>(out.size() + queue.size());
      }
    out.push_back(std::move(node));
  }
  return out;
}

std::vector<uint8_t> encode_header(const RTreeBuild& t) {
  ByteWriter w;
  w.put(rtree_page::kVersion);
  w.put(t.page_size);
  w.put(t.max_entries);
  w.put(t.min_entries);
  w.put(t.height());
  w.put(uint32_t{0});  // root node index
  w.put(static_cast<uint64_t>(t.nodes.size()));
  w.put(t.object_count);
  w.put(static_cast<uint32_t>(t.method));
  w.put(uint32_t{0});
  Aabb bounds = t.bounds;
  if (bounds.empty()) bounds = Aabb{Vec3(0.0f), Vec3(0.0f)};
  put_box(w, bounds);
  std::vector<uint8_t> page = std::move(w.bytes());
  page.resize(t.page_size, 0);
  return page;
}

}  // namespace

RTreeBuild build_rtree(std::span<const Aabb> boxes, const RTreeParams& params, uint32_t page_size) {
  const uint32_t capacity = rtree_page_capacity(page_size);
  RTreeBuild t;
  t.page_size = page_size;
  t.method = params.method;
  t.max_entries = params.max_entries ? params.max_entries : capacity;
  t.min_entries = params.min_entries ? params.min_entries : std::max<uint32_t>(2, t.max_entries * 2 / 5);
  if (t.max_entries < 4 || t.max_entries > capacity)
    fail("rtree", "fan-out M = " + std::to_string(t.max_entries) + " must lie in [4, " + std::to_string(capacity) +
                      "] for " + std::to_string(page_size) + "-byte pages");
  if (t.min_entries < 2 || t.min_entries > t.max_entries / 2)
    fail("rtree", "minimum fill m = " + std::to_string(t.min_entries) + " must lie in [2, M/2 = " +
                      std::to_string(t.max_entries / 2) + "]");
  if (boxes.size() > UINT32_MAX) fail("rtree", "more than 2^32 objects");
  t.object_count = boxes.size();
  std::vector<RTreeEntry> entries;
  entries.reserve(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    entries.push_back({boxes[i], static_cast<uint32_t>(i)});
    t.bounds.extend(boxes[i]);
  }
  std::vector<RTreeNode> nodes;
  uint32_t root = 0;
  if (params.method == RTreeMethod::kStr && !entries.empty()) {
    std::tie(nodes, root) = str_pack(std::move(entries), t.max_entries);
  } else {
    InsertionBuilder b(t.max_entries, t.min_entries);
    for (const RTreeEntry& e : entries) b.insert(e);
    nodes = std::move(b.nodes());
    root = b.root();
  }
  t.nodes = breadth_first(nodes, root);
  return t;
}

std::vector<uint8_t> encode_rtree_section(const RTreeBuild& tree) {
  std::vector<uint8_t> bytes = encode_header(tree);
  for (const RTreeNode& node : tree.nodes) {
    const std::vector<uint8_t> page = rtree_page::encode_node(node, tree.page_size);
    bytes.insert(bytes.end(), page.begin(), page.end());
  }
  return bytes;
}

void write_rtree_section(const RTreeBuild& tree, WorldWriter& writer) {
  if (writer.page_size() != tree.page_size) fail("rtree", "internal: built for another page size");
  writer.begin_section(kRTreeSection);
  writer.write(encode_header(tree));
  for (const RTreeNode& node : tree.nodes) writer.write(rtree_page::encode_node(node, tree.page_size));
  writer.end_section();
}

RTreeBuild add_rtree_to_world(const std::string& path, const RTreeParams& params) {
  const World world(path);
  std::vector<Aabb> boxes(world.object_count());
  for (ObjectId id = 0; id < world.object_count(); ++id) boxes[id] = world.object(id).bounds;
  RTreeBuild tree = build_rtree(boxes, params, world.file().page_size());
  WorldWriter w(path, world.file().page_size());
  constexpr uint64_t kChunk = 1 << 20;
  for (const SectionInfo& s : world.file().sections()) {
    if (s.name == kRTreeSection) continue;
    w.begin_section(s.name);
    for (uint64_t at = 0; at < s.bytes; at += kChunk) w.write(world.file().read(s, at, std::min(kChunk, s.bytes - at)));
    w.end_section();
  }
  write_rtree_section(tree, w);
  w.finish();
  return tree;
}

}  // namespace cellwalk
