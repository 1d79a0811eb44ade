// HDoV thesis ch. 6, §6.1 and §6.2 (digest 000 §2.3, §4 "Memory scene tree"): the k-d scene tree
// as stored in its tree file and held in memory, with the node-id hash of §6.2.2. The file is a
// world-format file (paged, checksummed; docs/format.md) with the sections of
// docs/scene-tree.md, "Tree file"; its builder is scene_tree_build.cpp.
#include <xxhash.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/lod/dov_level.hpp"
#include "cellwalk/systems/scene_tree/scene_tree.hpp"
#include "core/bytes.hpp"
#include "systems/scene_tree/scene_tree_format.hpp"

namespace cellwalk {
namespace scene_tree_format {

uint64_t world_identity(const World& world) {
  const std::vector<uint8_t> objects = world.file().read_all("objects");
  const std::vector<uint8_t> lods = world.file().read_all("lods");
  XXH3_state_t* state = XXH3_createState();
  XXH3_64bits_reset(state);
  XXH3_64bits_update(state, objects.data(), objects.size());
  // Each level's entry without its offset (its first 8 of 24 bytes): a disk order that moves
  // the levels (`pvs --disk-order`) keeps the world the tree was built from.
  constexpr size_t kEntry = 24, kOffset = 8;
  for (size_t at = 0; at + kEntry <= lods.size(); at += kEntry)
    XXH3_64bits_update(state, lods.data() + at + kOffset, kEntry - kOffset);
  const uint64_t hash = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  return hash;
}

std::string params_json(const SceneTreeParams& params, uint64_t identity, size_t objects) {
  nlohmann::ordered_json j = {{"version", kVersion},
                              {"world_identity", identity},
                              {"objects", objects},
                              {"lod_ratio", params.lods.ratio},
                              {"lod_levels", params.lods.levels},
                              {"lod_min_triangles", params.lods.min_triangles},
                              {"lod_simplifier", int(params.lods.simplifier)}};
  return j.dump();
}

}  // namespace scene_tree_format

namespace {

// Reads and checks the node table: every index in range, children after their parent, each
// object in exactly one leaf, leaf counts and boxes consistent.
std::vector<SceneTreeNode> read_nodes(const std::vector<uint8_t>& bytes, const std::string& where,
                               std::span<const uint32_t> lod_counts, size_t level_table_size) {
  ByteReader in(bytes, where + ": section " + scene_tree_format::kNodes);
  const uint32_t count = in.get<uint32_t>("node count");
  const size_t objects = lod_counts.size();
  if (objects == 0 || count != 2 * objects - 1) in.error("node count " + std::to_string(count) + " does not fit " + std::to_string(objects) + " objects");
  if (count > in.remaining() / scene_tree_format::kNodeRecordBytes) in.error("node count " + std::to_string(count) + " past the end");
  std::vector<SceneTreeNode> nodes(count);
  std::vector<uint8_t> seen(objects, 0);
  for (uint32_t i = 0; i < count; ++i) {
    SceneTreeNode& n = nodes[i];
    const std::vector<float> box = in.get_array<float>(6, "box");  // in order: arguments are not
    n.box.min = Vec3(box[0], box[1], box[2]);
    n.box.max = Vec3(box[3], box[4], box[5]);
    n.parent = in.get<uint32_t>("parent");
    n.child[0] = in.get<uint32_t>("child");
    n.child[1] = in.get<uint32_t>("child");
    n.object = in.get<uint32_t>("object");
    n.leaf_count = in.get<uint32_t>("leaf count");
    n.first_level = in.get<uint32_t>("first level");
    n.level_count = in.get<uint32_t>("level count");
    const std::string node = "node " + std::to_string(i) + ": ";
    if ((i == 0) != (n.parent == kNoNode) || (i > 0 && n.parent >= i)) in.error(node + "bad parent");
    if (n.is_leaf()) {
      if (n.object >= objects || seen[n.object]++) in.error(node + "bad or repeated object");
      if (n.child[0] != kNoNode || n.child[1] != kNoNode || n.leaf_count != 1 ||
          n.level_count != lod_counts[n.object])
        in.error(node + "inconsistent leaf");
    } else {
      for (NodeIndex c : n.child)
        if (c <= i || c >= count) in.error(node + "bad child");
      if (uint64_t(n.first_level) + n.level_count > level_table_size) in.error(node + "levels out of range");
    }
  }
  // Parents and leaf counts must agree with the children (checked after all are read).
  for (uint32_t i = 0; i < count; ++i) {
    const SceneTreeNode& n = nodes[i];
    if (n.is_leaf()) continue;
    if (nodes[n.child[0]].parent != i || nodes[n.child[1]].parent != i ||
        uint64_t(nodes[n.child[0]].leaf_count) + nodes[n.child[1]].leaf_count != n.leaf_count)
      in.error("node " + std::to_string(i) + ": children disagree with their parent");
  }
  if (in.remaining() != 0) in.error("trailing bytes");
  return nodes;
}

std::vector<AggregateLevel> read_levels(const std::vector<uint8_t>& bytes, const std::string& where,
                                        uint64_t geometry_bytes) {
  ByteReader in(bytes, where + ": section " + scene_tree_format::kLevels);
  const uint32_t count = in.get<uint32_t>("level count");
  if (count > in.remaining() / scene_tree_format::kLevelRecordBytes) in.error("level count " + std::to_string(count) + " past the end");
  std::vector<AggregateLevel> levels(count);
  for (AggregateLevel& l : levels) {
    l.offset = in.get<uint64_t>("offset");
    l.bytes = in.get<uint32_t>("bytes");
    l.triangles = in.get<uint32_t>("triangles");
    if (l.offset > geometry_bytes || l.bytes > geometry_bytes - l.offset) in.error("level past the geometry section");
  }
  if (in.remaining() != 0) in.error("trailing bytes");
  return levels;
}

}  // namespace

scene_tree_format::Tables scene_tree_format::read_tables(const std::vector<uint8_t>& nodes, const std::vector<uint8_t>& levels,
                                         uint64_t geometry_bytes, std::span<const uint32_t> lod_counts,
                                         const std::string& where) {
  Tables t;
  t.levels = read_levels(levels, where, geometry_bytes);
  t.nodes = read_nodes(nodes, where, lod_counts, t.levels.size());
  return t;
}

SceneTree::SceneTree(const World& world, const std::string& path)
    : world_(world), file_(std::make_unique<WorldFile>(path, WorldFile::Options{})) {
  const std::string again = " (delete it to have it rebuilt)";
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(file_->read_all(scene_tree_format::kParams));
  } catch (const nlohmann::json::exception&) {
    fail(path, std::string("section ") + scene_tree_format::kParams + " is not JSON" + again);
  }
  if (!j.is_object() || j.value("version", 0) != scene_tree_format::kVersion) fail(path, "not a k-d scene tree of this version" + again);
  if (j.value("world_identity", uint64_t(0)) != scene_tree_format::world_identity(world) ||
      j.value("objects", uint64_t(0)) != world.object_count())
    fail(path, "was built from another world than " + world.file().path() + again);
  params_.lods.ratio = j.value("lod_ratio", 0.0f);
  params_.lods.levels = j.value("lod_levels", 0u);
  params_.lods.min_triangles = j.value("lod_min_triangles", size_t(0));
  params_.lods.simplifier = AggregateSimplifier(j.value("lod_simplifier", 0) == 1 ? 1 : 0);
  const uint64_t geometry_bytes = file_->section(scene_tree_format::kGeometry).bytes;
  std::vector<uint32_t> lod_counts(world.object_count());
  for (ObjectId o = 0; o < lod_counts.size(); ++o) lod_counts[o] = world.object(o).lod_count;
  scene_tree_format::Tables tables = scene_tree_format::read_tables(file_->read_all(scene_tree_format::kNodes), file_->read_all(scene_tree_format::kLevels),
                                                    geometry_bytes, lod_counts, path);
  levels_ = std::move(tables.levels);
  nodes_ = std::move(tables.nodes);
  leaf_of_.reserve(world.object_count());
  for (NodeIndex i = static_cast<NodeIndex>(nodes_.size()); i-- > 0;) {
    SceneTreeNode& n = nodes_[i];
    if (n.is_leaf()) {
      leaf_of_.emplace(n.object, i);
      n.leaf_triangles = world.lod(n.object, 0).triangles;
    } else {
      n.leaf_triangles = nodes_[n.child[0]].leaf_triangles + nodes_[n.child[1]].leaf_triangles;
    }
  }
}

SceneTree::~SceneTree() = default;

const std::string& SceneTree::path() const { return file_->path(); }

NodeIndex SceneTree::leaf_of(ObjectId object) const {
  const auto it = leaf_of_.find(object);
  return it == leaf_of_.end() ? kNoNode : it->second;
}

uint32_t SceneTree::triangles(NodeIndex n, uint32_t level) const {
  const SceneTreeNode& node = nodes_[n];
  return node.is_leaf() ? world_.lod(node.object, level).triangles : levels_[node.first_level + level].triangles;
}

Mesh SceneTree::read_aggregate(NodeIndex n, uint32_t level) const {
  const AggregateLevel& l = levels_.at(nodes_.at(n).first_level + level);
  const std::vector<uint8_t> bytes = file_->read(file_->section(scene_tree_format::kGeometry), l.offset, l.bytes);
  const std::string where = file_->path() + ": node " + std::to_string(n) + " level " + std::to_string(level);
  Mesh mesh = decode_mesh(bytes, where);
  if (mesh.triangle_count() != l.triangles) fail(where, "decodes to a different triangle count than its table says");
  return mesh;
}

uint64_t SceneTree::resident_bytes() const {
  // An unordered_map node holds the pair, a next pointer and the cached hash; plus a bucket.
  constexpr uint64_t kHashEntry = sizeof(std::pair<ObjectId, NodeIndex>) + 2 * sizeof(void*) + sizeof(void*);
  return nodes_.capacity() * sizeof(SceneTreeNode) + levels_.capacity() * sizeof(AggregateLevel) +
         leaf_of_.size() * kHashEntry + file_->resident_bytes() + sizeof(*this);
}

uint32_t nearest_level(const SceneTree& tree, NodeIndex n, double target) {
  return nearest_level(tree.node(n).level_count, target, [&](uint32_t l) { return tree.triangles(n, l); });
}

uint32_t finest_level_within(const SceneTree& tree, NodeIndex n, double cap) {
  const uint32_t levels = tree.node(n).level_count;
  for (uint32_t l = 0; l < levels; ++l)
    if (double(tree.triangles(n, l)) <= cap) return l;
  return levels - 1;
}

void count_selection(const SceneTree& tree, const std::vector<TreeSelection>& selection, TraversalStats& stats) {
  stats.triangles = stats.active_internal = stats.leaves = 0;
  for (const TreeSelection& s : selection) {
    stats.triangles += tree.triangles(s.node, s.level);
    ++(tree.node(s.node).is_leaf() ? stats.leaves : stats.active_internal);
  }
}

std::string default_scene_tree_path(const World& world) { return world.file().path() + ".scenetree"; }

std::unique_ptr<SceneTree> open_scene_tree(const World& world, const SceneTreeParams& params,
                                                const std::string& path,
                                                const std::function<void(uint64_t, uint64_t)>& progress) {
  const std::string file = path.empty() ? default_scene_tree_path(world) : path;
  if (std::filesystem::exists(file)) {
    WorldFile probe(file, {});
    const std::string stored = [&] {
      const std::vector<uint8_t> b = probe.read_all(scene_tree_format::kParams);
      return std::string(b.begin(), b.end());
    }();
    if (stored == scene_tree_format::params_json(params, scene_tree_format::world_identity(world), world.object_count()))
      return std::make_unique<SceneTree>(world, file);
  }
  build_scene_tree(world, file, params, progress);
  return std::make_unique<SceneTree>(world, file);
}

}  // namespace cellwalk
