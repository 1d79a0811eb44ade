// HDoV thesis §5.3 (Fig. 5.4, eqs. 5.3–5.6), §5.4 (cell flip) and §5.7 (DoV / DoV-Time node
// caches), digest §3.8, §3.11, §4: the threshold search over the disk HDoV-tree, its V-page
// lookups in each storage scheme, and the naive (cell, list-of-objects) baseline.
#include <algorithm>
#include <cmath>

#include "cellwalk/core/error.hpp"
#include "cellwalk/lod/dov_level.hpp"
#include "cellwalk/systems/visual/hdov_tree.hpp"
#include "core/bytes.hpp"

namespace cellwalk {
namespace {

constexpr uint32_t kNil = 0xFFFFFFFFu;

// Pages of `page_size` that the bytes [offset, offset + length) span.
uint64_t pages_spanned(uint64_t offset, uint64_t length, uint32_t page_size) {
  if (length == 0) return 0;
  return (offset + length - 1) / page_size - offset / page_size + 1;
}

std::unique_ptr<ReplacementPolicy> make_policy(const HdovCacheOptions& o) {
  switch (o.policy) {
    case HdovCacheOptions::Policy::kDov: return make_dov_policy();
    case HdovCacheOptions::Policy::kDovTime: return make_dov_time_policy(o.kappa, DovTimeClock::kQueries);
    case HdovCacheOptions::Policy::kDovTimeAccess: return make_dov_time_policy(o.kappa, DovTimeClock::kAccesses);
    default: return make_lru_policy();
  }
}

}  // namespace

uint32_t leaf_level(const World& world, ObjectId object, double dov, double max_dov) {
  const ObjectRecord& o = world.object(object);
  const double target = dov_triangle_target(dov_weight(dov, max_dov), world.lod(object, 0).triangles,
                                            world.lod(object, o.lod_count - 1).triangles);
  return nearest_level(o.lod_count, target, [&](uint32_t l) { return world.lod(object, l).triangles; });
}

HdovCacheOptions::Policy parse_hdov_cache_policy(const std::string& name) {
  if (name == "none") return HdovCacheOptions::Policy::kNone;
  if (name == "lru") return HdovCacheOptions::Policy::kLru;
  if (name == "dov") return HdovCacheOptions::Policy::kDov;
  if (name == "dt" || name == "dov-time") return HdovCacheOptions::Policy::kDovTime;
  if (name == "dt-access") return HdovCacheOptions::Policy::kDovTimeAccess;
  fail("cache policy \"" + name + "\"", "unknown; choose none, lru, dov, dt or dt-access");
}

const char* hdov_cache_policy_name(HdovCacheOptions::Policy policy) {
  switch (policy) {
    case HdovCacheOptions::Policy::kNone: return "none";
    case HdovCacheOptions::Policy::kLru: return "lru";
    case HdovCacheOptions::Policy::kDov: return "dov";
    case HdovCacheOptions::Policy::kDovTime: return "dt";
    case HdovCacheOptions::Policy::kDovTimeAccess: return "dt-access";
  }
  return "?";
}

struct HdovSearcher::Impl {
  const HdovTree& tree;
  VPageScheme scheme;
  HdovCacheOptions cache;
  MemoryBudget budget;
  std::unique_ptr<BufferManager> buffer;  // null without a cache
  CellId cell = 0;
  std::vector<uint32_t> vertical;                      // the vertical segment: a pointer per node
  std::vector<std::pair<uint32_t, uint32_t>> indexed;  // the IV segment: (node, pointer), by node
  uint64_t last_end = UINT64_MAX;                      // where the last V-page read ended
  uint64_t peak = 0;

  Impl(const HdovTree& t, VPageScheme s, const HdovCacheOptions& c)
      : tree(t), scheme(s), cache(c), budget(c.pages * t.page_size()) {
    if (c.policy != HdovCacheOptions::Policy::kNone && c.pages > 0)
      buffer = std::make_unique<BufferManager>(budget, make_policy(c));
  }

  uint64_t segment_bytes() const {
    return vertical.capacity() * sizeof(uint32_t) + indexed.capacity() * sizeof(indexed[0]);
  }

  void flip(CellId c, HdovCounters& counters) {
    if (c >= tree.cell_count()) fail("HDoV search", "cell " + std::to_string(c) + " is not in the tree");
    cell = c;
    const uint64_t n = tree.node_count();
    if (scheme == VPageScheme::kVertical) {
      const uint64_t offset = uint64_t(c) * n * 4;
      const std::vector<uint8_t> bytes = tree.read_bytes("vindex-v", offset, n * 4);
      counters.index_reads += pages_spanned(offset, n * 4, tree.page_size());
      counters.index_bytes += n * 4;
      ByteReader r(bytes, "vindex-v", offset);
      vertical = r.get_array<uint32_t>(n, "V-page pointers");
    } else if (scheme == VPageScheme::kIndexedVertical) {
      const auto [first, count] = tree.iv_directory()[c];
      const std::vector<uint8_t> bytes = tree.read_bytes("vindex-iv", uint64_t(first) * 8, uint64_t(count) * 8);
      counters.index_reads += pages_spanned(uint64_t(first) * 8, uint64_t(count) * 8, tree.page_size());
      counters.index_bytes += uint64_t(count) * 8;
      ByteReader r(bytes, "vindex-iv", uint64_t(first) * 8);
      indexed.assign(count, {});
      for (auto& [node, pointer] : indexed) {
        node = r.get<uint32_t>("segment node");
        pointer = r.get<uint32_t>("segment pointer");
      }
      if (!std::is_sorted(indexed.begin(), indexed.end())) r.error("segment not in node order");
    }
    peak = std::max(peak, resident());
  }

  // The V-page pointer of `node` in the current cell, nil when the node is invisible.
  uint32_t pointer(uint32_t node) const {
    if (scheme == VPageScheme::kVertical) return vertical.at(node);
    const auto it = std::lower_bound(indexed.begin(), indexed.end(), std::make_pair(node, uint32_t(0)));
    return it != indexed.end() && it->first == node ? it->second : kNil;
  }

  // The V-page of `node` in the current cell; nullopt when the node is invisible.
  std::optional<std::vector<VEntry>> vpage(uint32_t node, uint32_t entries, HdovCounters& counters) {
    uint64_t offset;
    if (scheme == VPageScheme::kHorizontal) {
      offset = (uint64_t(node) * tree.cell_count() + cell) * tree.vpage_size();
    } else {
      const uint32_t p = pointer(node);
      if (p == kNil) return std::nullopt;
      offset = uint64_t(p) * tree.vpage_size();
    }
    ++counters.vpage_reads;
    if (offset != last_end) ++counters.vpage_seeks;
    last_end = offset + tree.vpage_size();
    std::vector<VEntry> page = tree.read_vpage(scheme, offset, entries);
    const bool visible = std::any_of(page.begin(), page.end(), [](const VEntry& v) { return v.dov > 0; });
    if (!visible) return std::nullopt;  // horizontal keeps pages of invisible nodes
    return page;
  }

  std::shared_ptr<const HdovNode> node(uint32_t id, float dov, HdovCounters& counters) {
    ++counters.node_visits;
    const auto load = [&] { return std::make_shared<const HdovNode>(tree.read_node(id)); };
    if (!buffer) {
      ++counters.node_reads;
      return load();
    }
    EntryMeta meta;
    meta.dov = dov;
    const CacheResult r = buffer->get(id, meta, [&] { return LoadedItem{load(), tree.page_size()}; });
    if (!r.hit) ++counters.node_reads;
    peak = std::max(peak, resident());
    return BufferManager::get_as<HdovNode>(r);
  }

  uint64_t resident() const { return segment_bytes() + budget.used(); }

  void visit(const HdovNode& n, const std::vector<VEntry>& vd, const HdovSearchParams& p, std::vector<HdovPick>& out,
             HdovCounters& counters) {
    for (size_t e = 0; e < n.entries.size(); ++e) {
      const VEntry v = vd[e];
      if (v.dov == 0) continue;  // the digest's fix: `continue`, not `return`
      const uint32_t ref = n.entries[e].ref;
      if (n.leaf()) {
        const uint32_t level = leaf_level(tree.world(), ref, v.dov, p.max_dov);
        out.push_back({false, ref, level, tree.world().lod(ref, level).triangles});
        continue;
      }
      const std::shared_ptr<const HdovNode> child = node(ref, v.dov, counters);
      if (stops(*child, v, p)) {
        const double r = v.dov / p.eta;  // in (0, 1]
        const double target = dov_triangle_target(r, child->lods.front().triangles, child->lods.back().triangles);
        const auto count = static_cast<uint32_t>(child->lods.size());
        const uint32_t level = nearest_level(count, target, [&](uint32_t l) { return child->lods[l].triangles; });
        out.push_back({true, ref, level, child->lods[level].triangles});
        continue;
      }
      const std::optional<std::vector<VEntry>> child_vd = vpage(ref, static_cast<uint32_t>(child->entries.size()), counters);
      if (!child_vd) fail("HDoV search", "node " + std::to_string(ref) + " has DoV > 0 in its parent but no visible entry (damaged V-data)");
      visit(*child, *child_vd, p, out, counters);
    }
  }

  // Fig. 5.4's stopping rule: DoV <= η and eq. 5.4, h(1 + log_M s) < log_M n. With the node's
  // own m (objects below), h = log_M m and s = (T_lod / T_leaves)^(1/h), eq. 5.3's
  // m·f·s^h < f·n reads T_lod < (T_leaves / m)·n: the finest internal LOD costs fewer
  // triangles than the n visible objects at their mean size (docs/visual.md).
  static bool stops(const HdovNode& child, const VEntry& v, const HdovSearchParams& p) {
    if (child.lods.empty() || double(v.dov) > p.eta) return false;
    return double(child.lods.front().triangles) * child.objects < double(child.leaf_triangles) * v.nvo;
  }
};

HdovSearcher::HdovSearcher(const HdovTree& tree, VPageScheme scheme, const HdovCacheOptions& cache)
    : impl_(std::make_unique<Impl>(tree, scheme, cache)) {}
HdovSearcher::~HdovSearcher() = default;

void HdovSearcher::flip(CellId cell, HdovCounters& counters) {
  impl_->flip(cell, counters);
  cell_ = cell;
}

void HdovSearcher::search(const HdovSearchParams& params, std::vector<HdovPick>& out, HdovCounters& counters) {
  if (!cell_) fail("HDoV search", "no cell: flip() first");
  impl_->last_end = UINT64_MAX;  // a search's first V-page read is a seek
  if (impl_->buffer) impl_->buffer->begin_query({});  // DoV-Time's clock: one tick per search
  const std::shared_ptr<const HdovNode> root = impl_->node(0, 1.0f, counters);
  const auto vd = impl_->vpage(0, static_cast<uint32_t>(root->entries.size()), counters);
  if (vd) impl_->visit(*root, *vd, params, out, counters);
}

uint64_t HdovSearcher::resident_bytes() const { return impl_->resident(); }
uint64_t HdovSearcher::peak_bytes() const { return impl_->peak; }
BufferCounters HdovSearcher::cache_counters() const { return impl_->buffer ? impl_->buffer->counters() : BufferCounters{}; }

void naive_search(const HdovTree& tree, CellId cell, double max_dov, std::vector<HdovPick>& out,
                  HdovCounters& counters) {
  if (cell >= tree.cell_count()) fail("naive search", "cell " + std::to_string(cell) + " is not in the tree");
  const uint64_t first = tree.naive_directory()[cell], end = tree.naive_directory()[cell + 1];
  const std::vector<uint8_t> bytes = tree.read_bytes("naive-lists", first, end - first);
  counters.list_reads += pages_spanned(first, end - first, tree.page_size());
  ByteReader r(bytes, "naive-lists", first);
  while (r.remaining() > 0) {
    const auto object = r.get<uint32_t>("object id");
    const auto dov = r.get<float>("object DoV");
    if (object >= tree.world().object_count() || !(dov > 0) || !std::isfinite(dov)) r.error("bad list record");
    const uint32_t level = leaf_level(tree.world(), object, dov, max_dov);
    out.push_back({false, object, level, tree.world().lod(object, level).triangles});
  }
}

}  // namespace cellwalk
