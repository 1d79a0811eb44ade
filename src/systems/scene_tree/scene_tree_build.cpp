// HDoV thesis §6.2.1 (digest 000 §2.3 "Memory tree" preprocessing) and §5.6 (digest §3.10): the
// k-d tree over a world's objects [Bentley 1975, the thesis's ref. 6] and its internal LODs,
// made bottom-up from the children's coarsest levels by build_aggregate_lods (lod.hpp, shared
// with the disk HDoV-tree), so that a parent's finest LOD has fewer triangles than its
// children's coarsest together. Writes the tree file read by scene_tree.cpp.
#include <algorithm>
#include <numeric>
#include <span>
#include <unordered_map>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/scene_tree/scene_tree.hpp"
#include "cellwalk/lod/lod.hpp"
#include "cellwalk/store/mesh_codec.hpp"
#include "core/bytes.hpp"
#include "systems/scene_tree/scene_tree_format.hpp"

namespace cellwalk {
namespace {

// Median splits on the longest axis of the objects' centres (ties by id, so the tree is
// deterministic), one object per leaf, nodes appended in depth-first order.
class KdSplitter {
 public:
  explicit KdSplitter(const World& world) : world_(world) {
    centres_.reserve(world.object_count());
    for (ObjectId id = 0; id < world.object_count(); ++id) centres_.push_back(world.object(id).bounds.center());
  }

  std::vector<SceneTreeNode> build() {
    std::vector<ObjectId> ids(world_.object_count());
    std::iota(ids.begin(), ids.end(), 0u);
    split(ids, kNoNode);
    return std::move(nodes_);
  }

 private:
  NodeIndex split(std::span<ObjectId> ids, NodeIndex parent) {
    const auto me = static_cast<NodeIndex>(nodes_.size());
    nodes_.emplace_back();
    nodes_[me].parent = parent;
    if (ids.size() == 1) {
      const ObjectRecord& o = world_.object(ids[0]);
      nodes_[me].object = ids[0];
      nodes_[me].box = o.bounds;
      nodes_[me].level_count = o.lod_count;
      return me;
    }
    Aabb extent;
    for (ObjectId id : ids) extent.extend(centres_[id]);
    const Vec3 size = extent.size();
    const int axis = size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
    const size_t mid = ids.size() / 2;
    std::nth_element(ids.begin(), ids.begin() + std::ptrdiff_t(mid), ids.end(), [&](ObjectId a, ObjectId b) {
      const float ca = centres_[a][axis], cb = centres_[b][axis];
      return ca < cb || (ca == cb && a < b);
    });
    const NodeIndex left = split(ids.first(mid), me);
    const NodeIndex right = split(ids.subspan(mid), me);
    SceneTreeNode& n = nodes_[me];
    n.child[0] = left;
    n.child[1] = right;
    n.box = nodes_[left].box;
    n.box.extend(nodes_[right].box);
    n.leaf_count = nodes_[left].leaf_count + nodes_[right].leaf_count;
    return me;
  }

  const World& world_;
  std::vector<Vec3> centres_;
  std::vector<SceneTreeNode> nodes_;
};

Mesh coarsest_level(const World& world, ObjectId id) {
  const uint32_t level = world.object(id).lod_count - 1;
  return world.decode_level(id, level, world.read_level(id, level));
}

std::vector<uint8_t> node_table(const std::vector<SceneTreeNode>& nodes) {
  ByteWriter w;
  w.put(static_cast<uint32_t>(nodes.size()));
  for (const SceneTreeNode& n : nodes) {
    const float box[6] = {n.box.min.x, n.box.min.y, n.box.min.z, n.box.max.x, n.box.max.y, n.box.max.z};
    w.put_array(std::span<const float>(box));
    for (uint32_t v : {n.parent, n.child[0], n.child[1], n.object, n.leaf_count, n.first_level, n.level_count})
      w.put(v);
  }
  return std::move(w.bytes());
}

std::vector<uint8_t> level_table(const std::vector<AggregateLevel>& levels) {
  ByteWriter w;
  w.put(static_cast<uint32_t>(levels.size()));
  for (const AggregateLevel& l : levels) {
    w.put(l.offset);
    w.put(l.bytes);
    w.put(l.triangles);
  }
  return std::move(w.bytes());
}

void write_text(WorldWriter& writer, const char* section, const std::string& text) {
  writer.begin_section(section);
  writer.write(std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  writer.end_section();
}

}  // namespace

void build_scene_tree(const World& world, const std::string& path, const SceneTreeParams& params,
                         const std::function<void(uint64_t, uint64_t)>& progress) {
  if (world.object_count() == 0) fail(world.file().path(), "has no objects to build a k-d scene tree over");
  const AggregateLodParams& lods = params.lods;
  if (!(lods.ratio > 0.0f && lods.ratio < 1.0f) || lods.levels < 1)
    fail("k-d scene tree", "level ratio must be in (0, 1) and internal levels at least 1");
  std::vector<SceneTreeNode> nodes = KdSplitter(world).build();
  std::vector<AggregateLevel> levels;
  WorldWriter writer(path);
  writer.begin_section(scene_tree_format::kGeometry);
  // Children have larger indices than parents: in reverse order every node comes after both of
  // its children. `coarsest` holds a done node's coarsest representation until its parent.
  std::unordered_map<NodeIndex, Mesh> coarsest;
  const uint64_t internal = nodes.size() / 2;
  uint64_t done = 0;
  for (NodeIndex i = static_cast<NodeIndex>(nodes.size()); i-- > 0;) {
    SceneTreeNode& n = nodes[i];
    if (n.is_leaf()) {
      coarsest.emplace(i, coarsest_level(world, n.object));
      continue;
    }
    std::vector<LodPart> parts;
    for (NodeIndex c : n.child)  // a leaf's part takes its object's colour; aggregates carry theirs
      parts.push_back({&coarsest.at(c), nodes[c].is_leaf() ? world.object(nodes[c].object).color : Rgba8(0)});
    std::vector<Mesh> aggregates = build_aggregate_lods(parts, lods);
    n.first_level = static_cast<uint32_t>(levels.size());
    n.level_count = static_cast<uint32_t>(aggregates.size());
    for (const Mesh& level : aggregates) {
      const std::vector<uint8_t> bytes = encode_mesh(level);
      levels.push_back({writer.section_offset(), static_cast<uint32_t>(bytes.size()),
                        static_cast<uint32_t>(level.triangle_count())});
      writer.write(bytes);
    }
    // A node too small to simplify has no LOD; its parent aggregates what it aggregated.
    Mesh mine = aggregates.empty() ? aggregate_lod_parts(parts) : std::move(aggregates.back());
    for (NodeIndex c : n.child) coarsest.erase(c);
    coarsest.emplace(i, std::move(mine));
    if (progress) progress(++done, internal);
  }
  writer.end_section();
  write_text(writer, scene_tree_format::kParams,
             scene_tree_format::params_json(params, scene_tree_format::world_identity(world), world.object_count()));
  writer.begin_section(scene_tree_format::kNodes);
  writer.write(node_table(nodes));
  writer.end_section();
  writer.begin_section(scene_tree_format::kLevels);
  writer.write(level_table(levels));
  writer.end_section();
  writer.finish();
}

}  // namespace cellwalk
