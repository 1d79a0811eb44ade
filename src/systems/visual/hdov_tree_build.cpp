// HDoV thesis §5.2.2, §5.6, Fig. 5.13 (digest §2.3, §3.10, §4): building the HDoV-tree — the
// R-tree, renumbered depth first; internal LODs bottom-up; per cell, the VD of every entry.
#include <algorithm>
#include <numeric>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/visual/hdov_tree.hpp"
#include "cellwalk/store/mesh_codec.hpp"

namespace cellwalk {
namespace {

// The R-tree's nodes (breadth first) as HDoV nodes in depth-first preorder.
std::vector<HdovNode> depth_first(const RTreeBuild& rtree) {
  std::vector<HdovNode> nodes;
  nodes.reserve(rtree.nodes.size());
  auto visit = [&](auto&& self, uint32_t index) -> uint32_t {
    const RTreeNode& source = rtree.nodes[index];
    const auto id = static_cast<uint32_t>(nodes.size());
    nodes.push_back({.height = source.height, .entries = source.entries});
    if (!source.leaf())
      for (size_t e = 0; e < source.entries.size(); ++e) {
        const uint32_t child = self(self, source.entries[e].ref);
        nodes[id].entries[e].ref = child;
      }
    return id;
  };
  visit(visit, 0);
  return nodes;
}

// The coarsest representation of each node, what its parent aggregates: its coarsest internal
// LOD, or (a node too small to simplify) the aggregate of its own parts.
struct LodBuilder {
  const World& world;
  const AggregateLodParams& params;
  std::vector<Mesh> coarsest;  // by node

  std::vector<Mesh> object_meshes(const HdovNode& node) const {
    std::vector<Mesh> meshes;
    for (const RTreeEntry& e : node.entries) {
      const uint32_t level = world.object(e.ref).lod_count - 1;
      meshes.push_back(world.decode_level(e.ref, level, world.read_level(e.ref, level)));
    }
    return meshes;
  }

  void build(uint32_t id, HdovNode& node, std::vector<uint8_t>& geometry) {
    std::vector<Mesh> objects;
    if (node.leaf()) objects = object_meshes(node);
    std::vector<LodPart> parts;
    for (size_t e = 0; e < node.entries.size(); ++e) {
      const uint32_t ref = node.entries[e].ref;
      if (node.leaf())
        parts.push_back({&objects[e], world.object(ref).color});
      else
        parts.push_back({&coarsest[ref], 0});  // internal LODs carry per-vertex colours
    }
    std::vector<Mesh> levels = build_aggregate_lods(parts, params);
    for (const Mesh& level : levels) {
      const std::vector<uint8_t> bytes = encode_mesh(level);
      node.lods.push_back({geometry.size(), static_cast<uint32_t>(bytes.size()),
                           static_cast<uint32_t>(level.triangle_count())});
      geometry.insert(geometry.end(), bytes.begin(), bytes.end());
    }
    coarsest[id] = levels.empty() ? aggregate_lod_parts(parts) : std::move(levels.back());
    if (!node.leaf())  // children's coarsest are no longer needed
      for (const RTreeEntry& e : node.entries) coarsest[e.ref] = Mesh{};
  }
};

// Objects below and their level-0 triangles, bottom-up (children have larger ids).
void count_below(const World& world, std::vector<HdovNode>& nodes) {
  for (size_t n = nodes.size(); n-- > 0;) {
    HdovNode& node = nodes[n];
    for (const RTreeEntry& e : node.entries) {
      if (node.leaf()) {
        node.objects += 1;
        node.leaf_triangles += world.lod(e.ref, 0).triangles;
      } else {
        node.objects += nodes[e.ref].objects;
        node.leaf_triangles += nodes[e.ref].leaf_triangles;
      }
    }
  }
}

// The VD of every node for one cell; `dov_of` holds each object's DoV (0 if not visible).
std::vector<std::vector<VEntry>> cell_vd(const std::vector<HdovNode>& nodes, const std::vector<float>& dov_of) {
  std::vector<std::vector<VEntry>> vd(nodes.size());
  std::vector<VEntry> total(nodes.size());  // Σ over a node's entries, what its parent entry gets
  for (size_t n = nodes.size(); n-- > 0;) {
    const HdovNode& node = nodes[n];
    std::vector<VEntry> entries(node.entries.size());
    VEntry sum;
    for (size_t e = 0; e < node.entries.size(); ++e) {
      const uint32_t ref = node.entries[e].ref;
      if (node.leaf())
        entries[e] = dov_of[ref] > 0 ? VEntry{dov_of[ref], 1} : VEntry{};
      else
        entries[e] = total[ref];
      sum.dov += entries[e].dov;
      sum.nvo += entries[e].nvo;
    }
    total[n] = sum;
    if (sum.dov > 0) vd[n] = std::move(entries);
  }
  return vd;
}

}  // namespace

uint64_t HdovTreeBuild::visible_nodes() const {
  uint64_t sum = 0;
  for (const auto& cell : vd)
    for (const auto& node : cell) sum += node.empty() ? 0 : 1;
  return sum;
}

HdovTreeBuild build_hdov_tree(const World& world, const ViewCellPartition& cells, const CellDovSource& dov,
                              const HdovBuildParams& params,
                              const std::function<void(uint64_t, uint64_t)>& progress) {
  std::vector<Aabb> boxes(world.object_count());
  for (ObjectId i = 0; i < boxes.size(); ++i) boxes[i] = world.object(i).bounds;
  const RTreeBuild rtree = build_rtree(boxes, {.max_entries = params.max_entries, .method = params.method},
                                       params.page_size);
  HdovTreeBuild tree;
  tree.params = params;
  tree.params.max_entries = rtree.max_entries;
  tree.object_count = world.object_count();
  tree.world_triangles = world.triangle_count();
  tree.cells = serialize_partition(cells);
  tree.cell_count = static_cast<uint32_t>(cells.cell_count());
  tree.nodes = depth_first(rtree);
  count_below(world, tree.nodes);

  const uint64_t steps = tree.nodes.size() + tree.cell_count;
  uint64_t done = 0;
  LodBuilder lods{world, params.lods, std::vector<Mesh>(tree.nodes.size())};
  for (size_t n = tree.nodes.size(); n-- > 0;) {
    lods.build(static_cast<uint32_t>(n), tree.nodes[n], tree.geometry);
    if (progress) progress(++done, steps);
  }
  std::vector<float> dov_of(world.object_count());
  tree.vd.resize(tree.cell_count);
  for (CellId c = 0; c < tree.cell_count; ++c) {
    std::fill(dov_of.begin(), dov_of.end(), 0.0f);
    // A skipped cell's V-data stay empty; its flag travels in the tree's cells, so a walk that
    // enters it is refused rather than shown nothing.
    if (const std::optional<VisibleSet> set = cells.cell(c).skipped ? std::nullopt : dov(c)) {
      if (set->dov.size() != set->objects.size())
        fail("HDoV-tree build", "cell " + std::to_string(c) + "'s visible set has no DoVs (compute it with the dov engine)");
      for (size_t i = 0; i < set->objects.size(); ++i) {
        if (set->objects[i] >= dov_of.size())
          fail("HDoV-tree build", "cell " + std::to_string(c) + " names object " + std::to_string(set->objects[i]) +
                                      ", the world has " + std::to_string(dov_of.size()));
        dov_of[set->objects[i]] = set->dov[i];
      }
    }
    tree.vd[c] = cell_vd(tree.nodes, dov_of);
    if (progress) progress(++done, steps);
  }
  return tree;
}

SchemeStorage formula_storage(VPageScheme scheme, uint64_t nodes, uint64_t cells, uint64_t visible_nodes,
                              uint64_t vpage_size) {
  constexpr uint64_t kPointer = 4, kInteger = 4, kDirectoryEntry = 8;
  switch (scheme) {
    case VPageScheme::kHorizontal:  // eq. 5.7
      return {.vpage_bytes = vpage_size * cells * nodes};
    case VPageScheme::kVertical:  // eq. 5.8
      return {.vpage_bytes = vpage_size * visible_nodes, .index_bytes = kPointer * nodes * cells};
    case VPageScheme::kIndexedVertical:  // eq. 5.9, plus the cell directory
      return {.vpage_bytes = vpage_size * visible_nodes,
              .index_bytes = (kPointer + kInteger) * visible_nodes,
              .directory_bytes = kDirectoryEntry * cells};
  }
  return {};
}

}  // namespace cellwalk
