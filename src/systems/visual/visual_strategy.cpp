// HDoV thesis §5.3 and §5.8.5 (digest §2.3 run time, §3.8): VISUAL's frame — find the
// viewpoint's cell; on a change, flip to the cell's V-page index segment and run the threshold
// search; draw the picks (objects at eq. 5.6's level, internal LODs at eq. 5.5's); the delta
// search reads only models not already buffered (the geometry caches' hits).
#include <filesystem>
#include <sstream>

#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/systems/visual/visual_strategy.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk {
namespace {

std::unique_ptr<HdovTree> open_tree(const World& world, const std::string& file) {
  const std::string path = file.empty() ? default_hdov_path(world.file().path()) : file;
  if (!std::filesystem::exists(path)) {
    std::unique_ptr<Progress> progress;
    build_visual_tree(world, path, HdovBuildParams{}, [&](uint64_t done, uint64_t total) {
      if (!progress) progress = std::make_unique<Progress>("HDoV-tree", total);
      progress->update(done);
    });
    if (progress) progress->finish();
  }
  return std::make_unique<HdovTree>(world, path);
}

// The largest V-page index segment a flip may hold.
uint64_t largest_segment(const HdovTree& tree, VPageScheme scheme) {
  if (scheme == VPageScheme::kVertical) return uint64_t(tree.node_count()) * 4;
  uint64_t largest = 0;
  if (scheme == VPageScheme::kIndexedVertical)
    for (const auto& [first, count] : tree.iv_directory()) largest = std::max<uint64_t>(largest, uint64_t(count) * 8);
  return largest;
}

}  // namespace

struct VisualStrategy::Impl {
  const World& world;
  VisualConfig config;
  double eta;
  std::unique_ptr<HdovTree> tree;
  std::unique_ptr<HdovSearcher> searcher;
  uint64_t fixed = 0;  // the tree's directory, node cache and segment (their limits)
  std::unique_ptr<MemoryBudget> lod_budget;
  std::unique_ptr<BufferManager> lods;  // decoded internal LODs
  std::unique_ptr<GeometryStore> store;
  std::vector<HdovPick> picks;
  std::vector<VisualQuery> queries;
  std::shared_ptr<const Mesh> current;
  uint64_t frame = 0, peak = 0;

  Impl(const World& w, const VisualConfig& c, const StrategyOptions& options)
      : world(w), config(c), eta(c.eta.value_or(options.eta)), tree(open_tree(w, c.tree_file)) {
    searcher = std::make_unique<HdovSearcher>(*tree, c.scheme, c.cache);
    const uint64_t cache = c.cache.policy == HdovCacheOptions::Policy::kNone ? 0 : c.cache.pages * tree->page_size();
    fixed = tree->resident_bytes() + cache + largest_segment(*tree, c.scheme) + sizeof(*this);
    const uint64_t budget = options.memory_budget_bytes;
    if (budget > 0 && fixed >= budget)
      fail("visual --budget", "the HDoV-tree's directory, node cache and V-page segment need " + byte_size_text(fixed) +
                                  ", more than the budget of " + byte_size_text(budget) + "; give a larger --budget");
    // What is left: a quarter for internal LODs, the rest for the objects' levels.
    const uint64_t rest = budget > 0 ? budget - fixed : 0;
    lod_budget = std::make_unique<MemoryBudget>(rest / 4);
    lods = std::make_unique<BufferManager>(*lod_budget, make_dov_time_policy());
    store = std::make_unique<GeometryStore>(w, budget > 0 ? rest - rest / 4 : 0, make_dov_time_policy(), 1,
                                            open_level_source(w, options.objects_db));
  }

  uint64_t resident() const {
    return tree->resident_bytes() + searcher->resident_bytes() + lod_budget->used() + store->resident_bytes() + sizeof(*this);
  }

  bool buffered(const HdovPick& p) const {
    return p.internal ? lods->contains(lod_key(p.id, p.level)) : store->buffer().contains(GeometryStore::key(p.id, p.level));
  }
  static CacheKey lod_key(uint32_t node, uint32_t level) { return (uint64_t(node) << 32) | level; }

  void query(CellId cell, FrameStats& stats) {
    Stopwatch watch;
    VisualQuery q{.frame = frame, .cell = cell};
    searcher->flip(cell, q.io);
    picks.clear();
    searcher->search({.eta = eta, .max_dov = config.max_dov}, picks, q.io);
    q.search_ms = watch.ms();
    q.picks = picks.size();
    for (const HdovPick& p : picks) q.new_models += buffered(p) ? 0 : 1;
    queries.push_back(q);
    stats.query_ms += q.search_ms;
  }
};

VisualStrategy::VisualStrategy(const World& world, const VisualConfig& config, const StrategyOptions& options)
    : impl_(std::make_unique<Impl>(world, config, options)) {}
VisualStrategy::~VisualStrategy() = default;

std::string VisualStrategy::name() const {
  const Impl& m = *impl_;
  // Every setting that changes what is drawn is in the name, so two runs in one table differ.
  std::ostringstream maxdov;
  maxdov << m.config.max_dov;
  return "visual:eta=" + std::to_string(m.eta) + ",maxdov=" + maxdov.str() +
         ",scheme=" + vpage_scheme_name(m.config.scheme) + ",policy=" + hdov_cache_policy_name(m.config.cache.policy);
}

void VisualStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Impl& m = *impl_;
  const std::optional<CellId> cell = m.tree->cells().locate(camera.position);
  // Outside the cells (or in a solid one) the last cell's result stays: VISUAL works only
  // inside precomputed cells (thesis §5.8.5, digest §6). A skipped cell has no DoVs at all:
  // keeping the last cell's would silently show the wrong objects.
  if (cell && m.tree->cells().cell(*cell).skipped) fail_in_skipped_cell(name(), m.tree->cells().cell(*cell), camera.position);
  if (cell && !m.tree->cells().cell(*cell).solid && cell != m.searcher->cell()) m.query(*cell, stats);
  items.clear();
  for (const HdovPick& p : m.picks) {
    if (p.internal)
      items.push_back({p.id, p.level, rgba8(200, 200, 200), DrawKind::kAggregate});
    else
      items.push_back({p.id, p.level, m.world.object(p.id).color});
  }
  ++m.frame;
  m.peak = std::max(m.peak, m.resident());
}

const Mesh* VisualStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  Impl& m = *impl_;
  m.current.reset();
  if (item.kind == DrawKind::kObject) {
    m.current = m.store->get(item.id, item.lod, EntryMeta{}, stats);
  } else {
    const uint32_t node = item.id;
    if (node >= m.tree->node_count()) return nullptr;
    Stopwatch watch;
    const CacheResult r = m.lods->get(Impl::lod_key(node, item.lod), EntryMeta{}, [&] {
      const HdovNode n = m.tree->read_node(node);
      if (item.lod >= n.lods.size()) fail("visual", "node " + std::to_string(node) + " has no LOD " + std::to_string(item.lod));
      auto mesh = std::make_shared<const Mesh>(m.tree->read_lod(n.lods[item.lod]));
      const uint64_t bytes = mesh->byte_size();
      return LoadedItem{std::move(mesh), bytes};
    });
    (r.hit ? stats.cache_hits : stats.cache_misses) += 1;
    if (!r.hit) stats.io_ms += watch.ms();
    if (!r.cached) return nullptr;  // larger than the LOD budget: not drawn rather than over budget
    m.current = BufferManager::get_as<Mesh>(r);
  }
  m.peak = std::max(m.peak, m.resident());
  return m.current.get();
}

uint64_t VisualStrategy::resident_bytes() const { return impl_->resident(); }
uint64_t VisualStrategy::peak_resident_bytes() const { return std::max(impl_->peak, impl_->resident()); }
const std::vector<VisualQuery>& VisualStrategy::queries() const { return impl_->queries; }

QueryTotals VisualStrategy::query_totals() const {
  QueryTotals t{.queries = impl_->queries.size()};
  for (const VisualQuery& q : impl_->queries) t.disk_ios += q.io.light_ios(), t.ms += q.search_ms;
  return t;
}

}  // namespace cellwalk
