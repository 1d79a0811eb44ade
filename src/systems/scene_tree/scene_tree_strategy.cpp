// HDoV thesis ch. 6 (digest 000 §2.3 run time, §3.12–§3.13): the frame of the memory HDoV scene
// tree — find the viewpoint's cell, replace the VDs on a change of cell, traverse (CONV, VSC or
// PB), draw the selected leaves and internal LODs.
#include "systems/scene_tree/scene_tree_strategy.hpp"

#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/error.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"

namespace cellwalk {
namespace {

// What StoredPvs holds: the stored sections (cells, pvs, dov) and its two offset tables.
uint64_t stored_dov_bytes(const World& world, const visibility::StoredPvs& dov) {
  uint64_t bytes = 0;
  for (const char* s : {visibility::kCellsSection, visibility::kPvsSection, visibility::kDovSection})
    bytes += world.file().section(s).bytes;
  return bytes + 2 * sizeof(uint64_t) * (dov.partition().cell_count() + 1) + sizeof(dov);
}

std::unique_ptr<SceneTree> open_tree(const World& world, const std::string& file) {
  std::unique_ptr<Progress> progress;
  auto tree = open_scene_tree(world, SceneTreeParams{}, file, [&](uint64_t done, uint64_t total) {
    if (!progress) progress = std::make_unique<Progress>("k-d scene tree", total);
    progress->update(done);
  });
  if (progress) progress->finish();
  return tree;
}

}  // namespace

SceneTreeStrategy::SceneTreeStrategy(const World& world, const StrategyOptions& options, Traversal traversal)
    : world_(world), traversal_(traversal), options_(options), tree_(open_tree(world, options.scene_tree_file)) {
  fixed_bytes_ = tree_->resident_bytes() + sizeof(*this);
  aggregates_.resize(tree_->levels().size());
  for (NodeIndex n = 0; n < tree_->nodes().size(); ++n) {
    const SceneTreeNode& node = tree_->node(n);
    if (node.is_leaf()) continue;
    for (uint32_t l = 0; l < node.level_count; ++l) aggregates_[node.first_level + l] = tree_->read_aggregate(n, l);
  }
  for (const Mesh& m : aggregates_) fixed_bytes_ += m.byte_size() + sizeof(Mesh);
  if (traversal_ != Traversal::kConv) {
    if (!world.file().has_section(visibility::kDovSection))
      fail(world.file().path(), "has no stored DoVs for " + name() + ": run `cellwalk pvs " + world.file().path() +
                                    " --engine dov --cells grid:SIZE` first");
    dov_ = std::make_unique<visibility::StoredPvs>(world);
    vd_ = std::make_unique<SceneTreeVisibility>(*tree_);
    fixed_bytes_ += stored_dov_bytes(world, *dov_) + vd_->resident_bytes();
  }
  const uint64_t budget = options.memory_budget_bytes;
  if (budget > 0 && fixed_bytes_ >= budget)
    fail(name() + " --budget", "the scene tree, its internal LODs and visibility data need " +
                                   byte_size_text(fixed_bytes_) + " resident, more than the budget of " +
                                   byte_size_text(budget) + "; give a larger --budget");
  store_ = std::make_unique<GeometryStore>(world, budget > 0 ? budget - fixed_bytes_ : 0, nullptr, 1,
                                           open_level_source(world, options.objects_db));
}

SceneTreeStrategy::~SceneTreeStrategy() = default;

std::string SceneTreeStrategy::name() const {
  switch (traversal_) {
    case Traversal::kConv: return "conv";
    case Traversal::kVsc: return "hdov-vsc";
    case Traversal::kPb: return "hdov-pb";
  }
  return "?";
}

void SceneTreeStrategy::follow_cell(const Vec3& position) {
  const std::optional<CellId> cell = dov_->partition().locate(position);
  if (cell && dov_->partition().cell(*cell).skipped) fail_in_skipped_cell(name(), dov_->partition().cell(*cell), position);
  if (cell && cell != cell_) {
    const std::optional<VisibleSet> set = dov_->set(*cell);
    if (set) {  // a solid cell has none: keep the last
      vd_->assign(*set);
      cell_ = cell;
      ++cell_changes_;
    }
  }
  if (!cell_)
    fail(name(), "the camera at (" + std::to_string(position.x) + ", " + std::to_string(position.y) + ", " +
                     std::to_string(position.z) + ") is not in a view cell with stored DoVs; " +
                     "the HDoV scene tree works only inside them (thesis §6.2.2)");
}

void SceneTreeStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Stopwatch watch;
  const Frustum frustum(camera);
  switch (traversal_) {
    case Traversal::kConv:
      conv_traverse(*tree_, frustum, selection_, last_);
      break;
    case Traversal::kVsc:
      follow_cell(camera.position);
      vsc_traverse(*tree_, *vd_, frustum, {.eta = options_.eta, .dov_leaf_levels = options_.dov_levels},
                   selection_, last_);
      break;
    case Traversal::kPb:
      follow_cell(camera.position);
      pb_traverse(*tree_, *vd_, frustum, {.budget = options_.polygon_budget, .dov_levels = options_.dov_levels}, selection_, last_);
      break;
  }
  items.clear();
  for (const TreeSelection& s : selection_) {
    const SceneTreeNode& node = tree_->node(s.node);
    // Internal LODs are aggregates of their node (their meshes carry colours).
    if (node.is_leaf())
      items.push_back({node.object, s.level, world_.object(node.object).color});
    else
      items.push_back({s.node, s.level, rgba8(200, 200, 200), DrawKind::kAggregate});
  }
  stats.query_ms += watch.ms();
}

const Mesh* SceneTreeStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  current_.reset();  // the renderer has uploaded it: let the store evict it
  if (item.kind == DrawKind::kAggregate) {
    const NodeIndex n = item.id;
    if (n >= tree_->nodes().size() || item.lod >= tree_->node(n).level_count) return nullptr;
    return &aggregates_[tree_->node(n).first_level + item.lod];
  }
  EntryMeta meta;
  if (item.kind != DrawKind::kObject) return nullptr;
  if (vd_) meta.dov = (*vd_)[tree_->leaf_of(item.id)].dov;
  current_ = store_->get(item.id, item.lod, meta, stats);
  return current_.get();
}

}  // namespace cellwalk
