// The strategies of the memory HDoV scene tree (HDoV thesis ch. 6, digest 000 §2.2 last column):
// `conv`, `hdov-vsc` and `hdov-pb` share the k-d scene tree, its resident internal LODs and the
// objects' geometry through the store; they differ only in the traversal that selects what to
// draw. VSC and PB also hold the world's stored per-cell DoVs and the tree's VDs, replaced when
// the camera enters another view cell (§6.2.2).
#pragma once

#include <memory>
#include <optional>

#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/systems/scene_tree/scene_tree.hpp"
#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk {

namespace visibility {
class StoredPvs;
}

class SceneTreeStrategy : public Strategy {
 public:
  enum class Traversal { kConv, kVsc, kPb };

  // Opens (or builds, see open_scene_tree) the world's k-d scene tree and decodes every
  // internal LOD. Everything resident — tree, internal LODs, stored DoVs, VDs — is charged to
  // options.memory_budget_bytes before the geometry store gets the rest. Throws Error if the
  // budget cannot hold it, or (VSC, PB) if the world has no stored DoVs.
  SceneTreeStrategy(const World& world, const StrategyOptions& options, Traversal traversal);
  ~SceneTreeStrategy() override;

  std::string name() const override;
  // Throws Error if the camera has never been inside a view cell with a visible set (VSC, PB):
  // the DoV exists only there (thesis §6.2.2). Outside the cells the last cell's VD is kept.
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  bool serves_every_level() const override { return true; }
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  uint64_t resident_bytes() const override { return fixed_bytes_ + store_->resident_bytes(); }
  uint64_t peak_resident_bytes() const override { return fixed_bytes_ + store_->peak_resident_bytes(); }

  // The last select()'s traversal (nodes visited, triangles, active internal nodes).
  const TraversalStats& last_traversal() const { return last_; }
  const SceneTree& tree() const { return *tree_; }
  // Cell changes so far (VD replacements).
  uint64_t cell_changes() const { return cell_changes_; }

 private:
  void follow_cell(const Vec3& position);

  const World& world_;
  const Traversal traversal_;
  const StrategyOptions options_;
  std::unique_ptr<SceneTree> tree_;
  std::vector<Mesh> aggregates_;  // every internal LOD, indexed like tree_->levels()
  std::unique_ptr<visibility::StoredPvs> dov_;
  std::unique_ptr<SceneTreeVisibility> vd_;
  std::optional<CellId> cell_;
  uint64_t cell_changes_ = 0;
  uint64_t fixed_bytes_ = 0;
  std::unique_ptr<GeometryStore> store_;
  std::vector<TreeSelection> selection_;
  TraversalStats last_;
  std::shared_ptr<const Mesh> current_;  // the mesh handed to the renderer for upload
};

}  // namespace cellwalk
