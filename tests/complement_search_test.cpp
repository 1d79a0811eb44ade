// CSearch (HDoV thesis §4.2.2, digest §3.3) as properties over random walks, checked against a
// brute-force oracle and against Boost.Geometry's R-tree: the union of complement results is
// what plain box queries load, results never repeat what the history returned, and REVIEW's
// strategy, with the object buffer's eviction and history cut, loads at every query what a box
// query would and fetches nothing twice while it is buffered.
#include <gtest/gtest.h>

#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>

#include <algorithm>
#include <set>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/systems/review/review.hpp"
#include "cellwalk/index/rtree.hpp"
#include "cellwalk/store/world.hpp"
#include "test_support.hpp"

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

// A world of the same random boxes with its paged R-tree, for ReviewStrategy.
std::string write_box_world(const test::TempDir& dir, const World3& w) {
  std::vector<Object> objects;
  for (size_t i = 0; i < w.boxes.size(); ++i) {
    Object o;
    o.id = ObjectId(i);
    o.mesh = test::box_mesh(w.boxes[i]);
    objects.push_back(std::move(o));
  }
  const std::string file = test::write_world(dir, objects, NavGraph{}, "boxes");
  RTreeParams params;
  params.max_entries = 12;
  add_rtree_to_world(file, params);
  return file;
}

// A camera wandering over the world at 40 m/s, turning and now and then walking back over old
// ground (the cells' random walk as a camera path).
CameraPath wandering_path(uint64_t seed, int frames) {
  Random rng(seed);
  Vec3 position(750, 20, 750);
  float yaw = 0;
  CameraPath path;
  for (int i = 0; i < frames; ++i) {
    yaw += float(rng.uniform(-4, 4));
    if (rng.chance(0.01)) yaw += 180;  // back over old cells
    const Vec3 step(-std::sin(glm::radians(yaw)), 0, -std::cos(glm::radians(yaw)));
    position = glm::clamp(position + step * 4.0f, Vec3(100, 20, 100), Vec3(1400, 20, 1400));
    path.frames.push_back({0.1 * i, position, yaw, -10.0f});
  }
  return path;
}

// REVIEW itself (through the Strategy interface) walking a path under a small object buffer, so
// that it evicts and cuts its history (Fig. 4.8 and the digest's fix). At every search, demand
// or prefetch, checked against the brute-force oracle and Boost: the results lie in the cell and
// together with what is buffered make up exactly what a plain box query of the cell would load;
// the results that are buffered (left by a query that did not fit, so its cell is not in the
// history) are exactly the ones the strategy skips: nothing is fetched twice while buffered.
// After a frame's query completes, the whole cell is buffered.
TEST(ComplementSearch, ReviewStrategyUnderEvictionLoadsWhatBoxQueriesWould) {
  test::TempDir dir;
  const World3 w = make_world(2500, 9, RTreeMethod::kLinearInsert);
  const World world(write_box_world(dir, w));
  ReviewStrategy review(world, parse_review_strategy_name("review:depth=150,sf=1.5,cache=0.032,buffer=0.25"),
                        StrategyOptions{});
  Strategy& strategy = review;
  auto buffered = [&](ObjectId id) {
    FrameStats scratch;
    return strategy.mesh(DrawItem{id, 0, {}}, scratch) != nullptr;
  };
  auto box_query = [&](const Aabb& cell) {  // the oracle, checked against Boost
    std::set<uint32_t> ids;
    for (uint32_t i = 0; i < w.boxes.size(); ++i)
      if (w.boxes[i].overlaps(cell)) ids.insert(i);
    EXPECT_EQ(ids, boost_query(w, cell));
    return ids;
  };
  uint64_t prefetches = 0, complement_skipped = 0;
  std::vector<uint64_t> buffered_results;  // per search, in the order of queries()
  review.set_search_observer([&](const ReviewQuery& q, std::span<const uint32_t> results) {
    prefetches += q.prefetch ? 1 : 0;
    const std::set<uint32_t> got(results.begin(), results.end());
    ASSERT_EQ(got.size(), results.size()) << "a result repeats";
    const std::set<uint32_t> plain = box_query(q.cell);
    buffered_results.push_back(0);
    for (uint32_t id : got) {
      buffered_results.back() += buffered(id) ? 1 : 0;
      ASSERT_TRUE(plain.count(id)) << "object " << id << " is not in the cell";
    }
    for (uint32_t id : plain) {
      ASSERT_TRUE(got.count(id) || buffered(id)) << "object " << id << " of the cell neither returned nor buffered";
      complement_skipped += got.count(id) ? 0 : 1;
    }
  });
  Camera camera;
  camera.fov_y_deg = 45;
  camera.aspect = 1;
  camera.near_plane = 0.5f;
  camera.far_plane = 5000;
  std::vector<DrawItem> items;
  for (const PathFrame& f : wandering_path(5, 500).frames) {
    apply(f, camera);
    FrameStats stats;
    stats.time = f.time;
    const size_t before = review.queries().size();
    strategy.select(camera, items, stats);
    if (review.queries().size() == before) continue;
    const ReviewQuery& q = review.queries().back();
    if (q.dropped) continue;
    for (uint32_t id : box_query(q.cell)) ASSERT_TRUE(buffered(id)) << "object " << id << " of the cell queried";
  }
  ASSERT_EQ(buffered_results.size(), review.queries().size());
  uint64_t evictions = 0, demand = 0, skipped = 0;
  for (size_t i = 0; i < buffered_results.size(); ++i) {
    const ReviewQuery& q = review.queries()[i];
    evictions += q.evictions;
    demand += q.prefetch ? 0 : 1;
    skipped += q.already_buffered;
    EXPECT_EQ(q.fetched + q.already_buffered + q.dropped, q.results) << "query " << i;
    if (q.dropped == 0) {  // a prefetch that did not fit stops counting at the first refusal
      EXPECT_EQ(q.already_buffered, buffered_results[i]) << "query " << i << ": a buffered result was fetched";
    }
  }
  EXPECT_LT(skipped * 20, complement_skipped) << "most of what is buffered is left out by CSearch itself";
  EXPECT_GT(evictions, 3u) << "the budget must force evictions and history cuts";
  EXPECT_GT(demand, 10u);
  EXPECT_GT(prefetches, 5u);
  EXPECT_GT(complement_skipped, 0u) << "CSearch must have left buffered objects out";
  EXPECT_EQ(review.duplicate_fetches(), 0u);
}

}  // namespace
}  // namespace cellwalk
