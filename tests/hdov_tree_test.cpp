// The disk HDoV-tree (HDoV thesis ch. 5): invariants of §4, the three storage schemes against
// eqs. 5.7–5.9, the threshold search against the naive (cell, list-of-objects) oracle, caches.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "cellwalk/core/error.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/systems/visual/visual_strategy.hpp"
#include "cellwalk/core/random.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

constexpr VPageScheme kSchemes[] = {VPageScheme::kHorizontal, VPageScheme::kVertical, VPageScheme::kIndexedVertical};

// A street world, a 2D grid of cells over it and random DoVs with the spatial coherence of real
// visibility: an object near the cell (within a tenth of the street) is visible from it with
// probability 0.8, DoVs spread over six decades (an oracle independent of any engine).
class HdovTreeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    world_ = new World(test::write_street_world(*dir_, 150, 7));
    CellRegion region = default_cell_region(world_->info().bounds, world_->info().nav, true);
    const float extent = region.bounds.size().x;
    cells_ = make_grid_partition(region, extent / 24).release();
    Random rng(11);
    sets_ = new std::vector<VisibleSet>(cells_->cell_count());
    for (CellId c = 0; c < cells_->cell_count(); ++c)
      for (ObjectId id = 0; id < world_->object_count(); ++id)
        if (std::abs(world_->object(id).bounds.center().x - cells_->cell(c).box.center().x) < extent / 10 &&
            rng.uniform() < 0.8) {
          VisibleSet& set = (*sets_)[c];
          set.objects.push_back(id);
          set.dov.push_back(float(std::pow(10.0, rng.uniform(-7, -1))));
        }
    HdovBuildParams params;
    params.max_entries = 4;
    build_ = new HdovTreeBuild(build_hdov_tree(*world_, *cells_, [](CellId c) { return std::optional((*sets_)[c]); }, params));
    path_ = dir_->file("world.hdov");
    write_hdov_tree(*build_, path_);
    tree_ = new HdovTree(*world_, path_);
  }
  static void TearDownTestSuite() {
    delete tree_;
    delete build_;
    delete sets_;
    delete cells_;
    delete world_;
    delete dir_;
  }
  static std::vector<HdovPick> search(VPageScheme scheme, CellId cell, double eta, HdovCounters* io = nullptr) {
    HdovSearcher s(*tree_, scheme, {.policy = HdovCacheOptions::Policy::kNone});
    HdovCounters counters;
    s.flip(cell, counters);
    std::vector<HdovPick> out;
    s.search({.eta = eta}, out, counters);
    if (io) *io = counters;
    return out;
  }
  static inline test::TempDir* dir_ = nullptr;
  static inline World* world_ = nullptr;
  static inline ViewCellPartition* cells_ = nullptr;
  static inline std::vector<VisibleSet>* sets_ = nullptr;
  static inline HdovTreeBuild* build_ = nullptr;
  static inline HdovTree* tree_ = nullptr;
  static inline std::string path_;
};

TEST_F(HdovTreeTest, EntryDovIsTheSumOfItsChildNodeAndVisibleNodesHaveVisibleChildren) {
  const auto& nodes = build_->nodes;
  ASSERT_GT(nodes.size(), 30u);
  uint64_t checked = 0;
  for (CellId c = 0; c < build_->cell_count; ++c) {
    std::vector<float> oracle(world_->object_count(), 0.0f);
    for (size_t i = 0; i < (*sets_)[c].objects.size(); ++i) oracle[(*sets_)[c].objects[i]] = (*sets_)[c].dov[i];
    for (size_t n = 0; n < nodes.size(); ++n) {
      const auto& vd = build_->vd[c][n];
      if (vd.empty()) continue;
      ASSERT_EQ(vd.size(), nodes[n].entries.size());
      for (size_t e = 0; e < vd.size(); ++e) {
        const uint32_t ref = nodes[n].entries[e].ref;
        EXPECT_GE(vd[e].dov, 0.0f);
        if (nodes[n].leaf()) {
          EXPECT_EQ(vd[e].dov, oracle[ref]);
          continue;
        }
        const auto& child = build_->vd[c][ref];
        float dov = 0;
        uint32_t nvo = 0;
        for (const VEntry& v : child) dov += v.dov, nvo += v.nvo;
        EXPECT_EQ(vd[e].dov, dov) << "cell " << c << " node " << n << " entry " << e;  // invariant 2
        EXPECT_EQ(vd[e].nvo, nvo);
        EXPECT_EQ(vd[e].dov > 0, !child.empty());  // invariant 3: a visible node has a visible child
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100u);
}

TEST_F(HdovTreeTest, ParentsFinestLodIsSmallerThanItsChildrensCoarsest) {
  uint64_t checked = 0;
  for (const HdovNode& node : build_->nodes) {
    if (node.lods.empty()) continue;
    for (size_t l = 1; l < node.lods.size(); ++l) EXPECT_LT(node.lods[l].triangles, node.lods[l - 1].triangles);
    uint64_t children = 0;
    bool known = true;
    for (const RTreeEntry& e : node.entries) {
      if (node.leaf()) {
        children += world_->lod(e.ref, world_->object(e.ref).lod_count - 1).triangles;
      } else if (build_->nodes[e.ref].lods.empty()) {
        known = false;
      } else {
        children += build_->nodes[e.ref].lods.back().triangles;
      }
    }
    if (!known) continue;
    EXPECT_LT(node.lods.front().triangles, children);
    ++checked;
  }
  EXPECT_GT(checked, 10u);
  // The file holds what the build made.
  for (uint32_t n = 0; n < tree_->node_count(); ++n) {
    const HdovNode read = tree_->read_node(n);
    ASSERT_EQ(read.entries.size(), build_->nodes[n].entries.size());
    ASSERT_EQ(read.lods.size(), build_->nodes[n].lods.size());
    for (const HdovLodRef& l : read.lods) EXPECT_EQ(tree_->read_lod(l).triangle_count(), l.triangles);
  }
}

TEST_F(HdovTreeTest, MeasuredStorageMatchesEquations57To59AndOrdersHorizontalVerticalIndexed) {
  const uint64_t visible = build_->visible_nodes();
  for (VPageScheme s : kSchemes) {
    const SchemeStorage measured = tree_->storage(s);
    const SchemeStorage formula = formula_storage(s, tree_->node_count(), tree_->cell_count(), visible, tree_->vpage_size());
    EXPECT_EQ(measured.vpage_bytes, formula.vpage_bytes) << vpage_scheme_name(s);
    EXPECT_EQ(measured.index_bytes, formula.index_bytes) << vpage_scheme_name(s);
    EXPECT_EQ(measured.directory_bytes, formula.directory_bytes) << vpage_scheme_name(s);
  }
  EXPECT_GT(tree_->storage(VPageScheme::kHorizontal).total(), 2 * tree_->storage(VPageScheme::kVertical).total());
  EXPECT_GT(tree_->storage(VPageScheme::kVertical).total(), tree_->storage(VPageScheme::kIndexedVertical).total());
}

TEST_F(HdovTreeTest, EtaZeroEqualsTheNaiveListOfObjectsInEveryScheme) {
  for (CellId c = 0; c < tree_->cell_count(); ++c) {
    std::vector<HdovPick> naive;
    HdovCounters io;
    naive_search(*tree_, c, 0.5, naive, io);
    std::sort(naive.begin(), naive.end());
    EXPECT_EQ(naive.size(), (*sets_)[c].objects.size());
    for (VPageScheme s : kSchemes) {
      std::vector<HdovPick> picks = search(s, c, 0.0);
      std::sort(picks.begin(), picks.end());
      EXPECT_EQ(picks, naive) << "cell " << c << " " << vpage_scheme_name(s);
    }
  }
}

TEST_F(HdovTreeTest, LargerEtaDrawsInternalLodsWithFewerTrianglesAndSameInEveryScheme) {
  uint64_t internal = 0;
  for (CellId c = 0; c < tree_->cell_count(); ++c) {
    auto triangles = [](const std::vector<HdovPick>& p) {
      uint64_t t = 0;
      for (const HdovPick& x : p) t += x.triangles;
      return t;
    };
    const std::vector<HdovPick> exact = search(VPageScheme::kIndexedVertical, c, 0.0);
    const std::vector<HdovPick> coarse = search(VPageScheme::kIndexedVertical, c, 0.05);
    EXPECT_LE(triangles(coarse), triangles(exact));
    for (const HdovPick& p : coarse) internal += p.internal;
    for (VPageScheme s : kSchemes) EXPECT_EQ(search(s, c, 0.05), coarse) << vpage_scheme_name(s);
  }
  EXPECT_GT(internal, 0u);
}

TEST_F(HdovTreeTest, FlipsAndSeeksOrderTheSchemesAsSection54Says) {
  HdovCounters h, v;
  for (CellId c = 0; c < tree_->cell_count(); ++c) {
    HdovCounters a, b, d;
    search(VPageScheme::kHorizontal, c, 0.0, &a);
    search(VPageScheme::kVertical, c, 0.0, &b);
    search(VPageScheme::kIndexedVertical, c, 0.0, &d);
    EXPECT_EQ(a.vpage_reads, b.vpage_reads);
    EXPECT_EQ(b.vpage_reads, d.vpage_reads);
    EXPECT_EQ(a.index_reads, 0u);
    EXPECT_LT(d.index_bytes, b.index_bytes);  // a flip reads visible nodes only
    h.vpage_seeks += a.vpage_seeks;
    v.vpage_seeks += b.vpage_seeks;
  }
  EXPECT_GT(h.vpage_seeks, v.vpage_seeks);  // a cell's V-pages lie together in DFS order
}

TEST_F(HdovTreeTest, NodeCachesHitOnRepeatedQueriesUnderEveryPolicy) {
  for (auto policy : {HdovCacheOptions::Policy::kLru, HdovCacheOptions::Policy::kDov, HdovCacheOptions::Policy::kDovTime,
                      HdovCacheOptions::Policy::kDovTimeAccess}) {
    HdovSearcher s(*tree_, VPageScheme::kIndexedVertical, {.policy = policy, .pages = tree_->node_count()});
    HdovCounters io;
    std::vector<HdovPick> out;
    s.flip(0, io);
    s.search({}, out, io);
    const uint64_t first_reads = io.node_reads;
    s.search({}, out, io);
    EXPECT_EQ(io.node_reads, first_reads) << hdov_cache_policy_name(policy);  // all hits the second time
    EXPECT_LE(s.resident_bytes(), uint64_t(tree_->node_count()) * tree_->page_size() + tree_->node_count() * 8);
    HdovSearcher small(*tree_, VPageScheme::kIndexedVertical, {.policy = policy, .pages = 2});
    small.flip(0, io);
    small.search({}, out, io);
    EXPECT_LE(small.cache_counters().hits + small.cache_counters().misses, io.node_visits);
  }
}

// DoV-Time with T in queries (§5.7, digest §3.11): within one query recency does not count, so
// the smaller DoV goes first; counted in accesses, 20 later requests outweigh a DoV gap of 0.009.
TEST(HdovDovTime, TimeAdvancesOncePerQueryNotPerAccess) {
  auto run = [](DovTimeClock clock) {
    auto policy = make_dov_time_policy(0.001, clock);
    policy->on_query({});
    policy->on_insert(1, {.dov = 0.01f});
    for (CacheKey k = 10; k < 30; ++k) policy->on_insert(k, {.dov = 0.5f});
    policy->on_insert(2, {.dov = 0.001f});
    return policy;
  };
  const auto per_query = run(DovTimeClock::kQueries);
  const auto per_access = run(DovTimeClock::kAccesses);
  EXPECT_EQ(per_query->victim(), CacheKey(2));   // 0.001 + κ·1 < 0.01 + κ·1
  EXPECT_EQ(per_access->victim(), CacheKey(1));  // 0.01 + κ·1 < 0.001 + κ·22
  // Twenty queries later key 2 is touched again: now its T is 21 queries ahead of key 1's.
  for (int q = 0; q < 20; ++q) per_query->on_query({});
  per_query->on_access(2, {.dov = 0.001f});
  EXPECT_EQ(per_query->victim(), CacheKey(1));  // 0.01 + κ·1 < 0.001 + κ·21
}

// Random inserts, hits, erases and query ticks against a brute-force DoV + κ·T (T in queries).
TEST(HdovDovTime, PerQueryClockMatchesBruteForceOracle) {
  struct Item {
    float dov;
    uint64_t query, access;
  };
  constexpr double kKappa = 0.001;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    auto policy = make_dov_time_policy(kKappa, DovTimeClock::kQueries);
    std::map<CacheKey, Item> oracle;
    Random rng(seed);
    uint64_t query = 0, access = 0;
    for (int step = 0; step < 3000; ++step) {
      const CacheKey key = CacheKey(rng.integer(0, 40));
      const int op = rng.integer(0, 99);
      const auto dov = float(rng.integer(0, 20)) * 0.0005f;  // ties happen
      if (op < 10) {
        policy->on_query({});
        ++query;
      } else if (!oracle.count(key)) {
        policy->on_insert(key, {.dov = dov});
        oracle[key] = {dov, query, ++access};
      } else if (op < 80) {
        policy->on_access(key, {.dov = dov});
        oracle[key] = {dov, query, ++access};
      } else {
        policy->on_erase(key);
        oracle.erase(key);
      }
      std::optional<CacheKey> expect;
      std::pair<double, uint64_t> best{0, 0};
      for (const auto& [k, it] : oracle) {
        const std::pair<double, uint64_t> score{double(it.dov) + kKappa * double(it.query), it.access};
        if (!expect || score < best) expect = k, best = score;
      }
      ASSERT_EQ(policy->victim(), expect) << "seed " << seed << " step " << step;
    }
  }
}

TEST_F(HdovTreeTest, DamagedPagesGiveOneClearError) {
  std::vector<uint8_t> page(64, 0);
  const float nan = std::nanf("");
  std::memcpy(page.data(), &nan, 4);
  EXPECT_THROW(decode_vpage(page, 4, "t"), Error);
  EXPECT_THROW(decode_vpage(std::vector<uint8_t>(8), 4, "t"), Error);
  std::vector<uint8_t> unused(32, 0);
  unused[24] = 1;
  EXPECT_THROW(decode_vpage(unused, 2, "t"), Error);
  std::vector<uint8_t> node(4096, 0);
  node[4] = 0xFF;  // entry count
  EXPECT_THROW(decode_hdov_node(node, "t"), Error);
  EXPECT_THROW(decode_hdov_node(std::vector<uint8_t>(10), "t"), Error);
}

TEST_F(HdovTreeTest, VisualStrategyDrawsTheSearchResultWithinItsBudget) {
  StrategyOptions options;
  options.memory_budget_bytes = 8 << 20;
  auto s = make_strategy("visual:eta=0.001,scheme=v,cache=8,policy=dov,tree=" + path_, *world_, options);
  Camera camera;
  camera.position = cells_->cell(0).box.center();
  std::vector<DrawItem> items;
  FrameStats stats;
  s->select(camera, items, stats);
  EXPECT_FALSE(items.empty());
  for (const DrawItem& item : items) EXPECT_NE(s->mesh(item, stats), nullptr);
  EXPECT_LE(s->peak_resident_bytes(), options.memory_budget_bytes);
  // Settings that change what is drawn tell two runs apart in a side-by-side table.
  auto full = make_strategy("visual:eta=0.001,scheme=v,cache=8,policy=dov,maxdov=0.000000001,tree=" + path_,
                            *world_, options);
  EXPECT_NE(s->name(), full->name());
  EXPECT_THROW(make_strategy("visual:scheme=diagonal", *world_, options), Error);
  EXPECT_THROW(make_strategy("visual:eta=2", *world_, options), Error);
}

TEST(HdovTreeTestConfig, VisualNameSettingsParseAndBadOnesFailByName) {
  const VisualConfig c = parse_visual_strategy_name("visual:eta=0.01,cache=5,scheme=h,tree=t.hdov");
  EXPECT_DOUBLE_EQ(c.eta.value_or(-1), 0.01);
  EXPECT_EQ(c.cache.pages, 5u);
  EXPECT_EQ(c.scheme, VPageScheme::kHorizontal);
  EXPECT_EQ(c.tree_file, "t.hdov");
  for (const char* bad : {"visual:eta=2", "visual:eta=x", "visual:foo=1", "visual:eta", "visualx"}) {
    try {
      parse_visual_strategy_name(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace cellwalk
