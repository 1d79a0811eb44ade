// CSearch (HDoV thesis §4.2.2, digest §3.3) as properties over random walks, checked against a
// brute-force oracle and against Boost.Geometry's R-tree: the union of complement results is
// what plain box queries load, results never repeat what the history returned, and with the
// object buffer's eviction and history cut nothing is fetched twice while buffered.
#include <gtest/gtest.h>

#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>

#include <algorithm>
#include <set>

#include "cellwalk/random.hpp"
#include "cellwalk/rtree.hpp"
#include "strategy/review_object_buffer.hpp"

namespace cellwalk {
namespace {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;
using BPoint = bg::model::point<float, 3, bg::cs::cartesian>;
using BBox = bg::model::box<BPoint>;
using BValue = std::pair<BBox, uint32_t>;

BBox to_boost(const Aabb& b) { return BBox(BPoint(b.min.x, b.min.y, b.min.z), BPoint(b.max.x, b.max.y, b.max.z)); }

struct World3 {
  std::vector<Aabb> boxes;
  bgi::rtree<BValue, bgi::quadratic<16>> boost_tree;
  std::unique_ptr<DiskRTree> tree;
};

World3 make_world(size_t n, uint64_t seed, RTreeMethod method) {
  World3 w;
  Random rng(seed);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 p(float(rng.uniform(0, 1500)), 0.0f, float(rng.uniform(0, 1500)));
    const Vec3 s(float(rng.uniform(2, 30)), float(rng.uniform(3, 60)), float(rng.uniform(2, 30)));
    w.boxes.push_back({p, p + s});
    w.boost_tree.insert({to_boost(w.boxes.back()), uint32_t(i)});
  }
  RTreeParams params;
  params.max_entries = 12;
  params.method = method;
  w.tree = std::make_unique<DiskRTree>(encode_rtree_section(build_rtree(w.boxes, params, 4096)));
  return w;
}

// A walk of cells: a box of a random size drifting and turning across the world.
std::vector<Aabb> random_walk(uint64_t seed, int steps) {
  Random rng(seed);
  Vec3 centre(750, 10, 750), heading(1, 0, 0);
  std::vector<Aabb> cells;
  for (int i = 0; i < steps; ++i) {
    const float turn = float(rng.uniform(-0.6, 0.6));
    heading = Vec3(heading.x * std::cos(turn) - heading.z * std::sin(turn), 0,
                   heading.x * std::sin(turn) + heading.z * std::cos(turn));
    centre += heading * float(rng.uniform(0, 90));
    if (centre.x < 100 || centre.x > 1400 || centre.z < 100 || centre.z > 1400) {  // stay in the world
      heading = -heading;
      centre = glm::clamp(centre, Vec3(100, 10, 100), Vec3(1400, 10, 1400));
    }
    if (rng.chance(0.1)) centre -= heading * 150.0f;  // walk back over old cells
    const Vec3 half(float(rng.uniform(40, 160)), 30, float(rng.uniform(40, 160)));
    cells.push_back({centre - half, centre + half});
  }
  return cells;
}

std::set<uint32_t> boost_query(const World3& w, const Aabb& cell) {
  std::vector<BValue> hits;
  w.boost_tree.query(bgi::intersects(to_boost(cell)), std::back_inserter(hits));
  std::set<uint32_t> ids;
  for (const BValue& v : hits) ids.insert(v.second);
  return ids;
}

TEST(ComplementSearch, COverlapIsNotCompletelyInside) {
  const Aabb cell{Vec3(0), Vec3(10)};
  EXPECT_FALSE(coverlaps({Vec3(1), Vec3(9)}, cell));
  EXPECT_FALSE(coverlaps(cell, cell));
  EXPECT_TRUE(coverlaps({Vec3(5), Vec3(11)}, cell));
  EXPECT_TRUE(coverlaps({Vec3(20), Vec3(30)}, cell));
  EXPECT_TRUE(coverlaps({Vec3(-1), Vec3(11)}, cell));
}

// Full history, no eviction: each result is exactly {o : o ∩ C ≠ ∅, o ∩ Cj = ∅ for all earlier
// Cj} (oracle and Boost), results are disjoint, their union is the union of box queries, and
// CSearch never visits more nodes than the box search of the same cell.
TEST(ComplementSearch, UnionOverARandomWalkEqualsPlainBoxQueries) {
  for (RTreeMethod method : {RTreeMethod::kLinearInsert, RTreeMethod::kStr}) {
    for (uint64_t seed : {1, 2, 3}) {
      const World3 w = make_world(2500, seed, method);
      RTreeCacheOptions options;
      options.policy = RTreeCacheOptions::Policy::kNone;
      RTreeNodeCache cache(*w.tree, options);
      std::vector<Aabb> history;
      std::set<uint32_t> complement_union, box_union;
      for (const Aabb& cell : random_walk(seed * 17, 60)) {
        std::vector<uint32_t> got;
        SearchCounters cs, bs;
        complement_search(cache, cell, history, got, cs);
        std::vector<uint32_t> plain;
        box_search(cache, cell, plain, bs);
        EXPECT_LE(cs.node_visits, bs.node_visits);
        std::set<uint32_t> earlier, expected;  // Boost: box query of C minus those of the history
        for (const Aabb& h : history) {
          const std::set<uint32_t> ids = boost_query(w, h);
          earlier.insert(ids.begin(), ids.end());
        }
        for (uint32_t id : boost_query(w, cell))
          if (!earlier.count(id)) expected.insert(id);
        std::set<uint32_t> oracle;
        for (uint32_t i = 0; i < w.boxes.size(); ++i)
          if (w.boxes[i].overlaps(cell) &&
              std::none_of(history.begin(), history.end(), [&](const Aabb& h) { return w.boxes[i].overlaps(h); }))
            oracle.insert(i);
        const std::set<uint32_t> got_set(got.begin(), got.end());
        ASSERT_EQ(got_set.size(), got.size()) << "a result repeats";
        ASSERT_EQ(got_set, oracle);
        ASSERT_EQ(got_set, expected);
        for (uint32_t id : got) ASSERT_TRUE(complement_union.insert(id).second) << "object " << id << " returned twice";
        const std::set<uint32_t> b = boost_query(w, cell);
        box_union.insert(b.begin(), b.end());
        ASSERT_EQ(std::set<uint32_t>(plain.begin(), plain.end()), b);
        history.push_back(cell);
      }
      EXPECT_EQ(complement_union, box_union);
    }
  }
}

// REVIEW's loop with the object buffer under a small budget: the history filter, the eviction
// (keep what overlaps the new cell) and the history cut. After every query the buffer holds
// every object of the current cell (what a plain box query would load), every object of every
// history cell (CSearch's invariant), and no query returned an object that was buffered.
TEST(ComplementSearch, EvictionCutsTheHistoryAndNothingIsFetchedTwiceWhileBuffered) {
  const World3 w = make_world(2500, 9, RTreeMethod::kLinearInsert);
  RTreeCacheOptions options;
  options.bytes = 8 * 4096;  // a small DPLRU cache on the way
  RTreeNodeCache cache(*w.tree, options);
  constexpr uint64_t kObjectBytes = 1000;
  review::ObjectBuffer buffer(200 * kObjectBytes);
  uint64_t evictions = 0, filtered = 0;
  for (const Aabb& cell : random_walk(5, 150)) {
    const std::vector<Aabb> history = buffer.filtered_history(cell);
    filtered += buffer.history().size() - history.size();
    std::vector<uint32_t> got;
    SearchCounters counters;
    complement_search(cache, cell, history, got, counters);
    const size_t group = buffer.begin_group(cell);
    for (uint32_t id : got) {
      ASSERT_FALSE(buffer.contains(id)) << "object " << id << " returned while buffered";
      if (!buffer.budget().try_reserve(kObjectBytes)) {
        buffer.evict_outside(std::span<const Aabb>(&cell, 1));
        ++evictions;
        ASSERT_TRUE(buffer.budget().try_reserve(kObjectBytes)) << "one cell must fit this test's buffer";
      }
      review::BufferedObject o;
      o.id = id;
      o.box = w.boxes[id];
      o.reservation = review::Reservation(buffer.budget(), kObjectBytes);
      ASSERT_TRUE(buffer.insert(group, std::move(o)));
    }
    buffer.record_cell(cell);
    for (uint32_t id : boost_query(w, cell)) ASSERT_TRUE(buffer.contains(id)) << "object " << id << " of the cell";
    for (const Aabb& h : buffer.history())
      for (uint32_t id : boost_query(w, h)) ASSERT_TRUE(buffer.contains(id)) << "object " << id << " of a history cell";
    ASSERT_LE(buffer.budget().used(), 200 * kObjectBytes);
  }
  EXPECT_GT(evictions, 3u);  // the budget did force evictions and history cuts
  EXPECT_GT(filtered, 0u);   // and the filter dropped cells
}

}  // namespace
}  // namespace cellwalk
