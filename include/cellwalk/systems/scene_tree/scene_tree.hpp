// The in-memory HDoV scene tree of HDoV thesis ch. 6 (digest 000 §2.3, §3.12–§3.13): a k-d
// tree over a world's objects whose internal nodes carry internal LODs (aggregates of their
// children's coarsest levels simplified bottom-up, §5.6 / digest §3.10) and whose nodes hold one
// visibility datum VD = (DoV, NVO) each, replaced when the viewer enters another view cell
// through a node-id hash (§6.2.2). Three traversals render from it: CONV (hierarchical view
// frustum culling, §6.3), VSC (DoV threshold + frustum culling, §6.1.1) and PB (polygon budget,
// §6.1.2, Fig. 6.2). Choices where the thesis is silent: docs/scene-tree.md.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "cellwalk/core/camera.hpp"
#include "cellwalk/lod/lod.hpp"
#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/visibility/visibility.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

using NodeIndex = uint32_t;
inline constexpr NodeIndex kNoNode = 0xFFFFFFFFu;
inline constexpr ObjectId kNoObject = 0xFFFFFFFFu;

// How internal LODs are made: build_aggregate_lods (lod.hpp), the one used by the disk
// HDoV-tree too, with build_lod_chain as the simplifier (see AggregateSimplifier). A node's parts are its two children's coarsest levels; it keeps up to
// lods.levels steps of lods.ratio below their aggregate, so its finest level has strictly
// fewer triangles than Σ children's coarsest (§5.6's constraint).
struct SceneTreeParams {
  // REQUIRES 0 < lods.ratio < 1, lods.levels >= 1.
  AggregateLodParams lods{.simplifier = AggregateSimplifier::kLodChain};
};

struct SceneTreeNode {
  Aabb box;                                 // of every object below
  NodeIndex parent = kNoNode;
  NodeIndex child[2] = {kNoNode, kNoNode};  // both set for an internal node, none for a leaf
  ObjectId object = kNoObject;              // a leaf's object
  uint32_t leaf_count = 1;                  // objects below
  uint32_t first_level = 0;                 // internal: index of its finest level in levels()
  uint32_t level_count = 0;                 // a leaf: its object's levels; internal: aggregates
  uint64_t leaf_triangles = 0;              // Σ level-0 triangles of the objects below (not stored)
  bool is_leaf() const { return object != kNoObject; }
};

// One internal LOD in the tree file's geometry section (mesh_codec encoding).
struct AggregateLevel {
  uint64_t offset = 0;
  uint32_t bytes = 0;
  uint32_t triangles = 0;
};

// The tree of one world, read from its tree file (layout in docs/scene-tree.md). Nodes are in
// depth-first order: the root is 0 and every child has a larger index than its parent.
// Thread-safety: const methods may be called concurrently.
class SceneTree {
 public:
  // Opens a tree file. Throws Error naming the file if it is damaged or was built from another
  // world (the message says to delete it so it is rebuilt).
  SceneTree(const World& world, const std::string& path);
  ~SceneTree();

  const World& world() const { return world_; }
  const std::string& path() const;
  const SceneTreeParams& params() const { return params_; }
  const std::vector<SceneTreeNode>& nodes() const { return nodes_; }
  const SceneTreeNode& node(NodeIndex n) const { return nodes_[n]; }
  const std::vector<AggregateLevel>& levels() const { return levels_; }
  // The node-id hash of §6.2.2: the leaf holding an object (kNoNode for an unknown id).
  NodeIndex leaf_of(ObjectId object) const;

  // Triangles of a node's level (0 = finest): the world's level for a leaf, the aggregate's
  // for an internal node. REQUIRES level < node(n).level_count.
  uint32_t triangles(NodeIndex n, uint32_t level) const;
  // An internal node's aggregate level, decoded from verified pages, with per-vertex colours.
  Mesh read_aggregate(NodeIndex n, uint32_t level) const;

  // Bytes the open tree holds: nodes, level table, hash, the file's tables.
  uint64_t resident_bytes() const;

 private:
  const World& world_;
  std::unique_ptr<WorldFile> file_;
  SceneTreeParams params_;
  std::vector<SceneTreeNode> nodes_;
  std::vector<AggregateLevel> levels_;
  std::unordered_map<ObjectId, NodeIndex> leaf_of_;
};

// The default tree file of a world: "<world>.scenetree".
std::string default_scene_tree_path(const World& world);

// Builds the tree of `world` (median splits on the longest axis of the objects' centres, one
// object per leaf) and its internal LODs, and writes it atomically to `path`. Reads every
// object's coarsest level. Called with (internal nodes done, total).
void build_scene_tree(const World& world, const std::string& path, const SceneTreeParams& params,
                         const std::function<void(uint64_t, uint64_t)>& progress = {});

// Opens `path` ("" = default_scene_tree_path), building it first when it is missing or was made
// with other parameters or from another world. Throws Error if it exists but is damaged.
std::unique_ptr<SceneTree> open_scene_tree(const World& world, const SceneTreeParams& params,
                                                const std::string& path = "",
                                                const std::function<void(uint64_t, uint64_t)>& progress = {});

// ---- Visibility data (§6.2.2) ----------------------------------------------------------------

// VD = (DoV, NVO): the degree of visibility of the node's objects from the current cell and
// the number of them that are visible.
struct VisibilityDatum {
  float dov = 0.0f;
  uint32_t nvo = 0;
};

// The VD of every node for the current view cell. A leaf's DoV is its object's region DoV (the
// stored value of the cell's visible set; NVO 1), an internal node's the sum of its children's
// (the cheap bound of §6.2.2, digest §3.9 [GAP]: it may exceed 1), computed bottom-up so
// `dov(n) == dov(child 0) + dov(child 1)` holds exactly in float arithmetic.
class SceneTreeVisibility {
 public:
  explicit SceneTreeVisibility(const SceneTree& tree);

  // Replaces every node's VD with that of a cell whose visible set is `set`. Touches only the
  // nodes on the root paths of the previous and the new visible leaves. Throws Error if the
  // set has no DoVs or names an object the tree does not hold.
  void assign(const VisibleSet& set);
  const VisibilityDatum& operator[](NodeIndex n) const { return vd_[n]; }
  uint64_t resident_bytes() const;

 private:
  const SceneTree& tree_;
  std::vector<VisibilityDatum> vd_;
  std::vector<NodeIndex> touched_;  // nodes whose VD is not zero, ascending
};

// ---- Traversals ------------------------------------------------------------------------------

// What a traversal draws: a node at one of its levels (a leaf's object, or an internal LOD).
struct TreeSelection {
  NodeIndex node = 0;
  uint32_t level = 0;
};

struct TraversalStats {
  uint64_t nodes_visited = 0;    // nodes whose box or VD was examined
  uint64_t triangles = 0;        // of the selection
  uint64_t active_internal = 0;  // internal nodes drawn as their own LOD (Fig. 6.3's yellow)
  uint64_t leaves = 0;           // leaves drawn (red)
  bool aborted = false;          // PB stopped after MAX_ATTEMPTS failed refinements
};

// CONV (§6.3): hierarchical view frustum culling over the same k-d tree; every object whose
// box meets the frustum at level 0. Equals per-object culling with Frustum::intersects.
void conv_traverse(const SceneTree& tree, const Frustum& frustum, std::vector<TreeSelection>& out,
                   TraversalStats& stats);

struct VscParams {
  double eta = 0.001;  // the DoV threshold η: subtrees with DoV <= η may be drawn as one LOD
  // Eq. 5.6 picks a leaf's level from its DoV (max_dov = 0.5 gives full detail only to objects
  // covering half the sphere); false draws every visible leaf at level 0.
  bool dov_leaf_levels = true;
  double max_dov = 0.5;
};

// VSC (§6.1.1 = the threshold search of §5.3, Fig. 5.4, plus frustum culling): skips nodes with
// DoV 0 (`continue`, the digest's fix) or outside the frustum; stops at an internal node when
// DoV <= η and its finest LOD costs less than its visible leaves would (eq. 5.3, see
// docs/scene-tree.md), choosing the level by eq. 5.5; draws leaves at eq. 5.6's level. With
// η = 0 it draws exactly the visible objects in the frustum.
void vsc_traverse(const SceneTree& tree, const SceneTreeVisibility& vd, const Frustum& frustum,
                  const VscParams& params, std::vector<TreeSelection>& out, TraversalStats& stats);

struct PbParams {
  uint64_t budget = 20000;     // the polygon budget I, triangles per frame
  // ComputeLodBudget's λ-target: LOD = min(λ·highest + (1 − λ)·lowest, B_i). false drops the
  // λ term (LOD = the finest within B_i), so an unlimited budget draws what VSC(0) at level 0
  // draws, as the thesis says PB(∞) does ("degrades to CONV").
  bool dov_levels = true;
  double max_dov = 0.5;        // MAXDOV of λ = min(DoV / MAXDOV, 1)
  uint32_t max_attempts = 8;   // failed fallbacks to a parent's LOD before the traversal stops
};

// PB (§6.1.2, Fig. 6.2) with frustum culling and the gaps resolved as docs/scene-tree.md says:
// children are refined in descending DoV with budgets B·d_i/D·k capping their level; a child
// that cannot be drawn within the remaining budget fails its parent, which then takes back
// (refunds) what its subtree selected and tries its own LOD. Never selects more than `budget`
// triangles.
void pb_traverse(const SceneTree& tree, const SceneTreeVisibility& vd, const Frustum& frustum,
                 const PbParams& params, std::vector<TreeSelection>& out, TraversalStats& stats);

// Sets stats.triangles, active_internal and leaves from a selection.
void count_selection(const SceneTree& tree, const std::vector<TreeSelection>& selection, TraversalStats& stats);

// The level of a node whose triangle count is nearest `target` (ties to the finer).
uint32_t nearest_level(const SceneTree& tree, NodeIndex n, double target);
// The finest level of a node with at most `cap` triangles; the coarsest if none has.
uint32_t finest_level_within(const SceneTree& tree, NodeIndex n, double cap);

}  // namespace cellwalk
