// Tests of the conservative from-region visibility engine: its parts (inscribed occluders,
// the single-occluder test, the cube depth buffer, vLOD §5.3's back-face test), scenes with a
// known answer, and the oracle: on random worlds, every object that any of many sampled rays
// from many points of the cell hits must be in the conservative set.
// Seeds: 001 vLOD §5.2–5.3; 000 HDoV thesis §5.5.1.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <optional>
#include <set>
#include <thread>

#include <glm/gtc/matrix_transform.hpp>

#include "cellwalk/precompute/conservative_visibility.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/lod/lod.hpp"
#include "cellwalk/core/random.hpp"
#include "test_support.hpp"
#include "precompute/backface_test.hpp"
#include "precompute/box_tree.hpp"
#include "precompute/depth_buffer.hpp"
#include "precompute/occluders.hpp"

namespace cellwalk {
namespace {

using test::box_mesh;
using test::RayOracle;
using Scene = test::ObjectScene;
using test::TempDir;
using visibility::CubeDepthBuffer;

Aabb box(Vec3 lo, Vec3 hi) { return {lo, hi}; }

Object object_of(ObjectId id, Mesh mesh) {
  Object o;
  o.id = id;
  o.name = "o" + std::to_string(id);
  o.bounds = bounds_of(mesh);
  o.mesh = std::move(mesh);
  return o;
}

std::vector<Object> boxes(const std::vector<Aabb>& list) {
  std::vector<Object> out;
  for (const Aabb& b : list) out.push_back(object_of(ObjectId(out.size()), box_mesh(b)));
  return out;
}

// ---- occluders ----------------------------------------------------------------------------

TEST(Occluders, BoxMeshGivesItselfAsOccluder) {
  const Aabb b = box({5, 0, -10}, {8, 10, 10});
  const auto found = visibility::inscribed_boxes(box_mesh(b));
  ASSERT_TRUE(found.closed);
  ASSERT_EQ(found.boxes.size(), 1u);
  EXPECT_TRUE(b.contains(found.boxes[0]));
  // Faces pushed out to the walls: exactly the box, so abutting boxes touch.
  EXPECT_EQ(found.boxes[0].min, b.min);
  EXPECT_EQ(found.boxes[0].max, b.max);
}

TEST(Occluders, OpenMeshGivesNone) {
  Mesh m = box_mesh(box({0, 0, 0}, {1, 1, 1}));
  m.indices.resize(m.indices.size() - 3);
  const auto found = visibility::inscribed_boxes(m);
  EXPECT_FALSE(found.closed);
  EXPECT_TRUE(found.boxes.empty());
}

// An L of two walls and a room with a door, each written double-sided (every triangle also in
// the opposite winding), and a double-sided box and triangle: every edge is used an even
// number of times and in both directions, so all four pass the closedness and orientation
// tests, and all their triangles lie in the faces of their bounding boxes; but the winding
// number is 0 everywhere. One side alone, the L, the room and the triangle are open: they
// enclose nothing and may give no occluder. The box encloses itself, double-sided or not.
TEST(Occluders, DoubleSidedSurfacesEncloseWhatOneSideEncloses) {
  Mesh l = test::double_sided(test::quad_mesh({0, 0, 0}, {0, 0, 10}, {0, 10, 10}, {0, 10, 0}));
  append(l, test::double_sided(test::quad_mesh({0, 0, 0}, {0, 10, 0}, {10, 10, 0}, {10, 0, 0})));
  Mesh triangle = test::double_sided(test::quad_mesh({5, 0, 0}, {5, 0, 10}, {5, 10, 10}, {5, 10, 0}));
  triangle.indices = {0, 1, 2, 4, 6, 5};
  const Aabb b = box({0, 0, 0}, {4, 5, 6});
  const Mesh two_sided_box = test::double_sided(box_mesh(b));
  for (const Mesh& m : {l, test::double_sided_room_with_door(), triangle, two_sided_box}) {
    ASSERT_TRUE(visibility::is_closed(m));
    ASSERT_TRUE(visibility::is_oriented(m));
  }
  for (const Mesh& m : {l, test::double_sided_room_with_door(), triangle})
    EXPECT_TRUE(visibility::inscribed_boxes(m).boxes.empty()) << m.triangle_count() << " triangles";
  const auto found = visibility::inscribed_boxes(two_sided_box);
  ASSERT_EQ(found.boxes.size(), 1u);
  EXPECT_EQ(found.boxes[0].min, b.min);
  EXPECT_EQ(found.boxes[0].max, b.max);
}

// An L of two overlapping boxes in one mesh: every inscribed box lies in the union, and the
// overlap counts as solid (winding number 2). Reversing one part's winding makes the mesh
// unoriented: parity then leaves the overlap out.
TEST(Occluders, BoxesLieInsideTheSolid) {
  const Aabb a = box({0, 0, 0}, {10, 3, 3}), b = box({0, 0, 0}, {3, 3, 12});
  Mesh m = box_mesh(a);
  append(m, box_mesh(b));
  ASSERT_TRUE(visibility::is_oriented(m));
  Mesh flipped = m;  // one triangle turned over: still closed, no longer oriented
  std::swap(flipped.indices[1], flipped.indices[2]);
  ASSERT_FALSE(visibility::is_oriented(flipped));
  Random rng(3);
  for (const Mesh* mesh : {&m, &flipped}) {
    const auto found = visibility::inscribed_boxes(*mesh);
    ASSERT_TRUE(found.closed);
    ASSERT_FALSE(found.boxes.empty());
    double largest = 0;
    for (const Aabb& o : found.boxes) {
      largest = std::max(largest, double(o.size().x * o.size().y * o.size().z));
      for (int i = 0; i < 2000; ++i) {
        const Vec3 p(rng.uniform(o.min.x, o.max.x), rng.uniform(o.min.y, o.max.y),
                     rng.uniform(o.min.z, o.max.z));
        if (mesh == &m)
          EXPECT_TRUE(a.contains(p) || b.contains(p));
        else
          EXPECT_NE(a.contains(p), b.contains(p));
      }
    }
    EXPECT_GE(largest, 60.0);  // most of an arm (3 × 3 × 10 m or 3 × 3 × 12 m)
  }
}

// A building as generators and modellers make it: a body with floor slabs through it and
// window boxes half sunk into its walls. The slabs' faces cut the whole mesh's interior into
// storeys, but the body is a closed part of its own and gives itself as the occluder.
TEST(Occluders, AssemblyPartsGiveTheirOwnBoxes) {
  const Aabb body = box({0, 0, 0}, {10, 30, 12});
  Mesh m = box_mesh(body);
  for (float y = 3; y < 30; y += 3) append(m, box_mesh(box({-0.2f, y, -0.2f}, {10.2f, y + 0.3f, 12.2f})));
  for (float y = 1; y < 29; y += 3)
    for (float x = 1; x < 9; x += 2) append(m, box_mesh(box({x, y, -0.1f}, {x + 1, y + 1.5f, 0.1f})));
  const auto found = visibility::inscribed_boxes(m);
  ASSERT_TRUE(found.closed);
  ASSERT_FALSE(found.boxes.empty());
  EXPECT_EQ(found.boxes[0].min, body.min);
  EXPECT_EQ(found.boxes[0].max, body.max);
  for (const Aabb& b : found.boxes) EXPECT_TRUE(body.contains(b) || b.size().y < 0.5f);
}

TEST(Occluders, BridgesSpanAbuttingBoxes) {
  const Aabb a = box({5, 0, -10}, {8, 10, 0}), b = box({5, 0, 0}, {8, 10, 10});
  const auto bridges = visibility::bridge_boxes(a, b);
  ASSERT_EQ(bridges.size(), 1u);
  EXPECT_EQ(bridges[0].min, Vec3(5, 0, -10));
  EXPECT_EQ(bridges[0].max, Vec3(8, 10, 10));
  EXPECT_TRUE(visibility::bridge_boxes(a, box({9, 0, 0}, {10, 1, 1})).empty());
}

TEST(Occluders, SingleOccluderTestFromEightCorners) {
  const Aabb cell = box({-1, 1, -1}, {1, 3, 1});
  const Aabb wall = box({5, 0, -10}, {5.2f, 10, 10});
  EXPECT_TRUE(visibility::occluder_hides(cell, wall, box({12, 1, -0.5f}, {13, 2, 0.5f})));
  // Reaching past the wall's end: seen from the cell's +z side.
  EXPECT_FALSE(visibility::occluder_hides(cell, wall, box({12, 1, 19}, {13, 2, 21})));
  // In front of the wall.
  EXPECT_FALSE(visibility::occluder_hides(cell, wall, box({3, 1, -0.5f}, {4, 2, 0.5f})));
}

// ---- cube depth buffer --------------------------------------------------------------------

TEST(CubeDepthBuffer, OccluderHidesWhatIsBehindItOnly) {
  CubeDepthBuffer depth(Vec3(0, 2, 0), 64);
  depth.add_occluder(box({5, -5, -10}, {6, 10, 10}));
  EXPECT_TRUE(depth.hidden(box({12, 1, -1}, {13, 3, 1})));
  EXPECT_FALSE(depth.hidden(box({3, 1, -1}, {4, 3, 1})));     // in front
  EXPECT_FALSE(depth.hidden(box({12, 1, 30}, {13, 3, 31})));  // beside
  EXPECT_FALSE(depth.hidden(box({-1, 1, -1}, {1, 3, 1})));    // around the eye
  EXPECT_GT(depth.covered_fraction(), 0.0);
  EXPECT_LT(depth.covered_fraction(), 0.5);
  depth.aim(Vec3(0, 2, 0));  // re-aimed, it forgets the occluder
  EXPECT_FALSE(depth.hidden(box({12, 1, -1}, {13, 3, 1})));
  EXPECT_EQ(depth.covered_fraction(), 0.0);
  depth.add_occluder(box({-6, -5, -10}, {-5, 10, 10}));  // and renders anew
  EXPECT_TRUE(depth.hidden(box({-13, 1, -1}, {-12, 3, 1})));
  EXPECT_FALSE(depth.hidden(box({12, 1, -1}, {13, 3, 1})));
}

// A box across several faces (around the eye's axes) is found hidden in all of them.
TEST(CubeDepthBuffer, OccluderAroundTheEyeHidesAcrossFaces) {
  CubeDepthBuffer depth(Vec3(0, 0, 0), 32);
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {-1.0f, 1.0f}) {
      Aabb shell{Vec3(-20), Vec3(20)};
      (side > 0 ? shell.min : shell.max)[axis] = side * 10.0f;
      depth.add_occluder(shell);
    }
  EXPECT_TRUE(depth.hidden(box({30, -3, -3}, {31, 3, 3})));
  EXPECT_TRUE(depth.hidden(box({-25, -25, -25}, {25, 25, -22})));
  EXPECT_FALSE(depth.hidden(box({8, -3, -3}, {9, 3, 3})));
}

// ---- back-face test (vLOD §5.3) -----------------------------------------------------------

// The engine skips every occluder (group) for which may_lower says no, re-aims one buffer per
// refinement level from box to box, and skips tiles and groups of tiles that no render can
// lower. Oracle: each render alone in a new buffer, where nothing can be skipped; their
// per-pixel minimum is what a buffer holding every occluder must hold. A buffer wanting every
// pixel is checked against it pixel by pixel, and one that demands the occludees must answer
// hidden() as that one does. 96² pixels make 2 × 2 groups of tiles per face.
TEST(CubeDepthBuffer, SkippingAndReaimingChangeNoPixelAndNoAnswer) {
  Random rng(23);
  auto random_box = [&](float spread, float size) {
    const Vec3 c(float(rng.uniform(-spread, spread)), float(rng.uniform(-spread / 4, spread / 4)),
                 float(rng.uniform(-spread, spread)));
    const Vec3 h(float(rng.uniform(0.2, size)), float(rng.uniform(0.2, size)), float(rng.uniform(0.2, size)));
    return Aabb{c - h, c + h};
  };
  constexpr int kResolution = 96;
  const Vec3 half(0.5f, 0.25f, 0.5f);
  int hidden = 0, skipped = 0, mismatched = 0, covered = 0;
  CubeDepthBuffer every(Vec3(0.0f), kResolution), culled(Vec3(0.0f), kResolution);
  for (int trial = 0; trial < 12; ++trial) {
    const Vec3 eye(float(rng.uniform(-2, 2)), float(rng.uniform(-1, 1)), float(rng.uniform(-2, 2)));
    every.aim(eye);
    culled.aim(eye);
    std::vector<Aabb> occludees;
    for (int i = 0; i < 60; ++i) occludees.push_back(random_box(80.0f, 3.0f));
    std::erase_if(occludees, [&](const Aabb& b) { return b.overlaps(Aabb{eye - Vec3(1.0f), eye + Vec3(1.0f)}); });
    for (const Aabb& b : occludees) culled.demand(b);
    std::vector<Aabb> occluders;
    for (int i = 0; i < 80; ++i) occluders.push_back(random_box(60.0f, 12.0f));
    std::erase_if(occluders, [&](const Aabb& b) { return b.overlaps(Aabb{eye - 2.0f * half, eye + 2.0f * half}); });
    std::sort(occluders.begin(), occluders.end(), [&](const Aabb& a, const Aabb& b) {
      return glm::length(a.center() - eye) < glm::length(b.center() - eye);
    });
    std::vector<float> oracle(size_t(6) * kResolution * kResolution, std::numeric_limits<float>::infinity());
    const auto render = [&](CubeDepthBuffer& d, const Aabb& o) {
      const Aabb eroded{o.min + half, o.max - half};
      if (!eroded.empty()) d.add_occluder(eroded);
      d.add_occluder_for_cell(o, half);
    };
    for (const Aabb& o : occluders) {
      if (every.may_lower(o)) render(every, o);
      if (culled.may_lower(o)) render(culled, o); else ++skipped;
      for (int call = 0; call < 2; ++call) {
        CubeDepthBuffer alone(eye, kResolution);
        const Aabb eroded{o.min + half, o.max - half};
        if (call == 0 && !eroded.empty()) alone.add_occluder(eroded);
        if (call == 1) alone.add_occluder_for_cell(o, half);
        for (int face = 0, k = 0; face < 6; ++face)
          for (int j = 0; j < kResolution; ++j)
            for (int i = 0; i < kResolution; ++i, ++k) oracle[size_t(k)] = std::min(oracle[size_t(k)], alone.depth(face, i, j));
      }
    }
    for (int face = 0, k = 0; face < 6; ++face)
      for (int j = 0; j < kResolution; ++j)
        for (int i = 0; i < kResolution; ++i, ++k) {
          mismatched += every.depth(face, i, j) != oracle[size_t(k)];
          covered += oracle[size_t(k)] != std::numeric_limits<float>::infinity();
        }
    for (const Aabb& b : occludees) {
      EXPECT_EQ(every.hidden(b), culled.hidden(b)) << trial;
      hidden += every.hidden(b);
    }
  }
  EXPECT_EQ(mismatched, 0);
  EXPECT_GT(covered, 10000);
  EXPECT_GT(hidden, 30);   // the scenes do occlude
  EXPECT_GT(skipped, 60);  // and the check does skip
}

// Boxes scattered over a 100 × 20 × 100 block, and query boxes among them, for the tree tests.
std::vector<Aabb> scattered_boxes(Random& rng, int count) {
  std::vector<Aabb> boxes;
  for (int i = 0; i < count; ++i) {
    const Vec3 c(float(rng.uniform(0, 100)), float(rng.uniform(0, 20)), float(rng.uniform(0, 100)));
    boxes.push_back({c, c + Vec3(float(rng.uniform(0.1, 8)), float(rng.uniform(0.1, 8)), float(rng.uniform(0.1, 8)))});
  }
  return boxes;
}

Aabb random_query(Random& rng) {
  const Vec3 c(float(rng.uniform(0, 100)), float(rng.uniform(0, 20)), float(rng.uniform(0, 100)));
  return {c, c + Vec3(float(rng.uniform(1, 20)))};
}

TEST(BoxTree, WalkFindsExactlyTheBoxesABruteForceScanFinds) {
  Random rng(29);
  const std::vector<Aabb> boxes = scattered_boxes(rng, 500);
  const visibility::BoxTree tree(boxes);
  std::vector<int> seen(boxes.size(), 0);
  tree.front_to_back(boxes[0], [](const Aabb&) { return true; }, [&](uint32_t i) { ++seen[i]; });
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), ptrdiff_t(boxes.size()));  // each once
  for (int q = 0; q < 50; ++q) {
    const Aabb query = random_query(rng);
    std::set<uint32_t> found, expected;
    tree.front_to_back(query, [&](const Aabb& group) { return group.overlaps(query); },
                       [&](uint32_t i) { if (boxes[i].overlaps(query)) found.insert(i); });
    for (uint32_t i = 0; i < boxes.size(); ++i)
      if (boxes[i].overlaps(query)) expected.insert(i);
    EXPECT_EQ(found, expected) << q;
  }
}

// Renumbered in leaf order, the items are a permutation of the old, and both walks find under
// the new numbers exactly the boxes a brute-force scan finds.
TEST(BoxTree, RenumberedInLeafOrderBothWalksFindWhatABruteForceScanFinds) {
  Random rng(31);
  const std::vector<Aabb> boxes = scattered_boxes(rng, 400);
  visibility::BoxTree tree(boxes);
  const std::vector<uint32_t> old = tree.number_in_leaf_order();
  ASSERT_EQ(old.size(), boxes.size());
  EXPECT_EQ(std::set<uint32_t>(old.begin(), old.end()).size(), boxes.size());
  std::vector<Aabb> renumbered;
  for (uint32_t o : old) renumbered.push_back(boxes[o]);
  int visited = 0;
  for (int q = 0; q < 50; ++q) {
    const Aabb query = random_query(rng);
    std::set<uint32_t> ordered, unordered, expected;
    const auto enter = [&](const Aabb& group) { return group.overlaps(query); };
    tree.front_to_back(query, enter, [&](uint32_t i) { if (renumbered[i].overlaps(query)) ordered.insert(i); });
    tree.depth_first(enter, [&](uint32_t i) { ++visited; if (renumbered[i].overlaps(query)) unordered.insert(i); });
    for (uint32_t i = 0; i < renumbered.size(); ++i)
      if (renumbered[i].overlaps(query)) expected.insert(i);
    EXPECT_EQ(ordered, expected) << q;
    EXPECT_EQ(unordered, expected) << q;
  }
  EXPECT_LT(visited, 50 * 400 / 4);  // the walks do cull
}

// The filter never rejects a box the exact slab test accepts, also for boxes that touch the
// segment only at an end or along a face (where rounding decides), and it does reject boxes.
TEST(SegmentFilter, AcceptsEveryBoxTheExactTestAccepts) {
  Random rng(37);
  int accepted = 0, rejected = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const float scale = trial % 2 ? 1.0f : 3000.0f;
    auto point = [&] {
      return scale * Vec3(float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1)));
    };
    const Vec3 a = point(), b = trial % 5 == 0 ? Vec3(a.x, a.y, point().z) : point();
    Aabb box{glm::min(point(), point()), glm::max(point(), point())};
    if (trial % 3 == 0) box.min.x = box.max.x = glm::mix(a.x, b.x, float(rng.uniform(0, 1)));  // grazing
    if (trial % 7 == 0) box.max = glm::max(box.min, b);                                         // at an end
    const bool exact = visibility::segment_meets_box(a, b, box);
    const bool filter = visibility::SegmentFilter(a, b).may_meet(box);
    if (exact) {
      EXPECT_TRUE(filter) << trial;
    }
    accepted += exact;
    rejected += !filter;
  }
  EXPECT_GT(accepted, 1000);
  EXPECT_GT(rejected, 1000);
}

TEST(BackfaceTest, ConeBoundsEveryDirection) {
  Random rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 centre = glm::normalize(Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
    const double spread = rng.uniform(0.0, 1.2);
    std::vector<Vec3> dirs;
    for (int i = 0; i < 20; ++i)
      dirs.push_back(centre + float(spread) * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
    const auto cone = visibility::bound_directions(dirs);
    if (!cone.bounded) continue;
    for (const Vec3& d : dirs) {
      const double angle = std::acos(std::clamp(double(glm::dot(glm::normalize(d), cone.axis)), -1.0, 1.0));
      EXPECT_LE(angle, cone.half_angle + 1e-4);
    }
  }
  const std::vector<Vec3> opposite{{1, 0, 0}, {-1, 0, 0}};
  EXPECT_FALSE(visibility::bound_directions(opposite).bounded);
}

TEST(BackfaceTest, BoxFacesSeenFromACellBeside) {
  const Mesh m = box_mesh(box({5, 0, -10}, {8, 10, 10}));
  const Aabb cell = box({-1, 1, -1}, {1, 3, 1});
  const auto back = visibility::back_facing_triangles(m, cell);
  int count = 0;
  for (size_t t = 0; t < back.size(); ++t) {
    const Vec3 n = glm::cross(m.positions[m.indices[3 * t + 1]] - m.positions[m.indices[3 * t]],
                              m.positions[m.indices[3 * t + 2]] - m.positions[m.indices[3 * t]]);
    // Only the −x face looks at the cell; every other face's plane has the cell behind it.
    EXPECT_EQ(back[t], n.x >= 0) << t;
    count += back[t];
  }
  EXPECT_EQ(count, 10);
}

// Hierarchical = exact per triangle, and sound against sampled viewpoints.
TEST(BackfaceTest, HierarchyMatchesPerTriangleOnBunny) {
  Mesh bunny = import_model(test::cgal_mesh("bunny00.off")).objects[0].mesh;
  const Aabb b = bounds_of(bunny);
  const Vec3 s = b.size();
  const Aabb cell{b.max + s * 0.3f, b.max + s * 0.5f};
  const auto back = visibility::back_facing_triangles(bunny, cell);
  Random rng(7);
  size_t flagged = 0;
  for (size_t t = 0; t < back.size(); ++t) {
    const Vec3 a = bunny.positions[bunny.indices[3 * t]];
    const Vec3 n = glm::cross(bunny.positions[bunny.indices[3 * t + 1]] - a,
                              bunny.positions[bunny.indices[3 * t + 2]] - a);
    bool exact = true;
    for (int i = 0; i < 8; ++i) {
      const Vec3 c(i & 1 ? cell.max.x : cell.min.x, i & 2 ? cell.max.y : cell.min.y,
                   i & 4 ? cell.max.z : cell.min.z);
      exact = exact && (glm::dot(glm::dvec3(n), glm::dvec3(c) - glm::dvec3(a)) < 0.0 ||
                        n == Vec3(0.0f));
    }
    if (n != Vec3(0.0f)) {
      ASSERT_EQ(back[t], exact) << t;
    }
    flagged += back[t];
    if (back[t] && t % 97 == 0) {
      const Vec3 e(rng.uniform(cell.min.x, cell.max.x), rng.uniform(cell.min.y, cell.max.y),
                   rng.uniform(cell.min.z, cell.max.z));
      EXPECT_LE(glm::dot(n, e - a), 0.0f);
    }
  }
  EXPECT_GT(flagged, back.size() / 4);
  std::printf("back-facing from the cell: %zu of %zu triangles\n", flagged, back.size());
}

// ---- the oracle ---------------------------------------------------------------------------

ConservativeParams only_shrinking() {
  ConservativeParams p;
  p.corner_test = false;
  return p;
}
ConservativeParams only_corners() {
  ConservativeParams p;
  p.occluder_shrinking = false;
  return p;
}


const Aabb kCell = box({-1, 1, -1}, {1, 3, 1});
const Aabb kTarget = box({12, 1, -0.5f}, {13, 2, 0.5f});

TEST(ConservativeEngine, InterfaceAndSolidCell) {
  Scene scene(boxes({box({5, 0, -10}, {8, 10, 10}), kTarget}));
  const auto engine = make_conservative_engine(*scene.world, {});
  EXPECT_TRUE(engine->conservative());
  EXPECT_EQ(engine->name(), "conservative");
  EXPECT_TRUE(engine->compute(ViewCell{0, kCell, 0, true}).objects.empty());
  const ConservativeStats* stats = conservative_stats(*engine);
  ASSERT_NE(stats, nullptr);
  EXPECT_EQ(stats->occluder_objects, 2u);
}

TEST(ConservativeEngine, WallHidesBoxBehindIt) {
  Scene scene(boxes({box({5, 0, -10}, {8, 10, 10}), kTarget}));
  for (const auto& params : {ConservativeParams{}, only_shrinking(), only_corners()}) {
    EXPECT_EQ(scene.visible(kCell, params), std::vector<ObjectId>{0});
  }
}

// Thinner than the cell: erosion by the whole cell leaves nothing (vLOD §5.2.2: occluders
// must be larger than the cell), but the per-face lateral shrinking keeps the wall's face and
// the 8-corner test needs no shrinking at all.
TEST(ConservativeEngine, ThinWallHides) {
  Scene scene(boxes({box({5, 0, -10}, {5.2f, 10, 10}), kTarget}));
  for (const auto& params : {ConservativeParams{}, only_shrinking(), only_corners()})
    EXPECT_FALSE(scene.sees(kCell, 1, params));
}

TEST(ConservativeEngine, GapInTheWallRevealsTheBox) {
  Scene scene(boxes({box({5, 0, -10}, {8, 10, -0.2f}), box({5, 0, 0.2f}, {8, 10, 10}), kTarget}));
  for (const auto& params : {ConservativeParams{}, only_shrinking(), only_corners()})
    EXPECT_TRUE(scene.sees(kCell, 2, params));
}

// The wall ends at z = 1, the cell's +z face: the box is seen only through rays leaving the
// cell near that face.
TEST(ConservativeEngine, BoxSeenFromOneCornerOnlyIsVisible) {
  const Aabb wall = box({3, 0, -10}, {4, 10, 1}), target = box({10, 1.5f, 0.5f}, {11, 2.5f, 1.3f});
  ASSERT_FALSE(visibility::segment_meets_box(Vec3(1, 2, 1), Vec3(10, 2, 1.3f), wall));
  ASSERT_TRUE(visibility::segment_meets_box(Vec3(0, 2, 0), Vec3(10, 2, 1.3f), wall));
  ASSERT_TRUE(visibility::segment_meets_box(Vec3(1, 2, 0.5f), Vec3(10, 2, 1.3f), wall));
  Scene scene(boxes({wall, target}));
  for (const auto& params : {ConservativeParams{}, only_shrinking(), only_corners()})
    EXPECT_TRUE(scene.sees(kCell, 1, params));
}

// Two abutting walls, the box behind their seam: neither wall hides it alone from the
// erosion's point of view, but the bridge across the seam (both solids) does.
TEST(ConservativeEngine, AbuttingWallsFuseAcrossTheSeam) {
  Scene scene(boxes({box({5, 0, -10}, {8, 10, 0}), box({5, 0, 0}, {8, 10, 10}), kTarget}));
  for (const auto& params : {ConservativeParams{}, only_shrinking(), only_corners()})
    EXPECT_FALSE(scene.sees(kCell, 2, params));
}

// Two staggered walls, apart: each hides part of a wide box, neither all of it. Only occluder
// fusion in the depth buffer (shrinking) hides it; the 8-corner test has no fusion.
TEST(ConservativeEngine, StaggeredWallsHideOnlyWithFusion) {
  const Aabb a = box({5, 0, -10}, {8, 10, 3}), b = box({10, 0, -3}, {13, 10, 10});
  const Aabb wide = box({16, 1, -9}, {17, 2, 9});
  Scene scene(boxes({a, b, wide}));
  EXPECT_FALSE(visibility::occluder_hides(kCell, a, wide));
  EXPECT_FALSE(visibility::occluder_hides(kCell, b, wide));
  // The joint shadow leaves little slack: pixel conservativeness may eat it at a low
  // resolution; 128² resolves it, and so does the default.
  ConservativeParams fine;
  fine.face_resolution = 128;
  ConservativeParams fine_shrinking = only_shrinking();
  fine_shrinking.face_resolution = 128;
  EXPECT_FALSE(scene.sees(kCell, 2, fine));
  EXPECT_FALSE(scene.sees(kCell, 2, fine_shrinking));
  EXPECT_FALSE(scene.sees(kCell, 2, ConservativeParams{}));
  EXPECT_TRUE(scene.sees(kCell, 2, only_corners()));
  // And the oracle agrees that it is hidden.
  RayOracle oracle(*scene.world);
  Random rng(11);
  EXPECT_EQ(oracle.visible(kCell, rng, 60, 40).count(2), 0u);
}

// The far field of a large city: two walls 100 m away, apart (no bridge), whose shadows
// overlap by only ~1.1° as seen from the cell. Every pixel must be covered by one shrunk wall
// alone, so at 64² per face (up to 1.8° per pixel) some leaf of the cell keeps a pixel across
// the overlap open and the box behind shows through it; at the default 256² every pixel lies
// wholly in one wall's shadow.
TEST(ConservativeEngine, FarWallsWhoseShadowsOverlapByLessThanACoarsePixelFuse) {
  const Aabb a = box({100, 0, -40}, {102, 40, 2.6f}), b = box({104, 0, 0.6f}, {106, 40, 40});
  const Aabb behind = box({120, 0, -8}, {121, 6, 8});
  Scene scene(boxes({a, b, behind}));
  EXPECT_FALSE(visibility::occluder_hides(kCell, a, behind));
  EXPECT_FALSE(visibility::occluder_hides(kCell, b, behind));
  ConservativeParams coarse = only_shrinking();
  coarse.face_resolution = 64;
  EXPECT_TRUE(scene.sees(kCell, 2, coarse));
  EXPECT_EQ(ConservativeParams{}.face_resolution, 256);
  EXPECT_FALSE(scene.sees(kCell, 2, only_shrinking()));
  EXPECT_FALSE(scene.sees(kCell, 2, ConservativeParams{}));
  RayOracle oracle(*scene.world);
  Random rng(13);
  EXPECT_EQ(oracle.visible(kCell, rng, 60, 40).count(2), 0u);
}

// A wall standing on the ground and a low box right behind it: from the cell (1 m tall) the
// wall shrunk by the cell's height opens a gap at its foot that the box's foot shows through;
// standing on the floor, nothing passes under the wall, so the grounded wall hides the box.
TEST(ConservativeEngine, GroundedOccluderHidesWhatIsAtItsFoot) {
  const Aabb wall = box({5, 0, -10}, {6, 4, 10}), low = box({7, 0, -1}, {8, 0.5f, 1});
  Scene scene(boxes({wall, low}));
  ConservativeParams grounded = only_shrinking(), floating = only_shrinking();
  grounded.refine_levels = floating.refine_levels = 0;
  floating.grounded_occluders = false;
  EXPECT_FALSE(scene.sees(kCell, 1, grounded));
  EXPECT_TRUE(scene.sees(kCell, 1, floating));
  RayOracle oracle(*scene.world);
  Random rng(12);
  EXPECT_EQ(oracle.visible(kCell, rng, 60, 40).count(1), 0u);
}

// A pillar narrower than the cell: shrunk by the whole cell it vanishes, but each quarter of
// the cell keeps most of it, and the box close behind it is in every quarter's shadow.
TEST(ConservativeEngine, RefiningTheCellHidesBehindSmallOccluders) {
  const Aabb cell = box({-2, 1, -2}, {2, 3, 2});
  const Aabb pillar = box({3, 0, -1.5f}, {3.5f, 10, 1.5f}), target = box({4, 1, -0.2f}, {4.2f, 2, 0.2f});
  Scene scene(boxes({pillar, target}));
  ConservativeParams coarse = only_shrinking(), refined = only_shrinking();
  coarse.refine_levels = 0;
  refined.refine_levels = 3;
  EXPECT_TRUE(scene.sees(cell, 1, coarse));
  EXPECT_FALSE(scene.sees(cell, 1, refined));
  RayOracle oracle(*scene.world);
  Random rng(13);
  EXPECT_EQ(oracle.visible(cell, rng, 80, 40).count(1), 0u);
}

// ---- double-sided surfaces ----------------------------------------------------------------

// Every object the ray oracle reaches from `points` points of the cell (8 corners first) is in
// the set of each configuration; returns what the oracle saw.
std::set<ObjectId> expect_keeps_what_rays_see(const Scene& scene, const Aabb& cell, uint64_t seed,
                                              int points, const std::string& what) {
  RayOracle oracle(*scene.world);
  Random rng(seed);
  const std::set<ObjectId> seen = oracle.visible(cell, rng, points, 40);
  for (const auto& params : {ConservativeParams{}, only_shrinking(), only_corners()}) {
    const std::vector<ObjectId> set = scene.visible(cell, params);
    for (ObjectId id : seen)
      EXPECT_TRUE(std::binary_search(set.begin(), set.end(), id)) << what << ": misses object " << id;
  }
  return seen;
}

// Two 10 × 10 m double-sided walls meeting at the edge x = z = 0 (one object), a 1 m cube
// beyond the L's open side, a ground slab. The segment from the cell's centre to the cube's
// crosses x = 0 at z = 15 and z = 0 at x = 15, both beyond the walls: the cube is in plain
// sight, though the L's bounding box lies across the line.
TEST(ConservativeEngine, CubeSeenPastAnLOfDoubleSidedWallsIsKept) {
  Mesh l = test::double_sided(test::quad_mesh({0, 0, 0}, {0, 0, 10}, {0, 10, 10}, {0, 10, 0}));
  append(l, test::double_sided(test::quad_mesh({0, 0, 0}, {0, 10, 0}, {10, 10, 0}, {10, 0, 0})));
  Scene scene({object_of(0, l), object_of(1, box_mesh(box({-5.5f, 4.5f, 19.5f}, {-4.5f, 5.5f, 20.5f}))),
               object_of(2, box_mesh(box({-30, -1, -30}, {30, 0, 30})))});
  const Aabb cell = box({19.5f, 4.5f, -5.5f}, {20.5f, 5.5f, -4.5f});
  EXPECT_EQ(expect_keeps_what_rays_see(scene, cell, 41, 24, "L").count(1), 1u);
}

// A room of double-sided quads, a 0.6 m cube inside it, the cell in front of the doorway: the
// cube is seen through the door.
TEST(ConservativeEngine, CubeSeenThroughTheDoorOfADoubleSidedRoomIsKept) {
  Scene scene({object_of(0, test::double_sided_room_with_door()),
               object_of(1, box_mesh(box({4.7f, 0.3f, 5.7f}, {5.3f, 0.9f, 6.3f})))});
  const Aabb cell = box({4.5f, 1.1f, -5.5f}, {5.5f, 2.1f, -4.5f});
  EXPECT_EQ(expect_keeps_what_rays_see(scene, cell, 43, 24, "room").count(1), 1u);
}

// Every constructed scene of the tests above, with its boxes written double-sided: a
// double-sided box stops the same rays and encloses the same volume (its winding number is 0,
// one side's is 1), so the engine must keep all that rays from the cell reach and prove just
// as much as with one-sided boxes.
TEST(ConservativeEngine, DoubleSidedVariantsOfTheScenesKeepWhatRaysSee) {
  struct Case {
    std::string name;
    std::vector<Aabb> boxes;
    Aabb cell;
  };
  const std::vector<Case> cases{
      {"wall", {box({5, 0, -10}, {8, 10, 10}), kTarget}, kCell},
      {"thin wall", {box({5, 0, -10}, {5.2f, 10, 10}), kTarget}, kCell},
      {"gap", {box({5, 0, -10}, {8, 10, -0.2f}), box({5, 0, 0.2f}, {8, 10, 10}), kTarget}, kCell},
      {"one corner", {box({3, 0, -10}, {4, 10, 1}), box({10, 1.5f, 0.5f}, {11, 2.5f, 1.3f})}, kCell},
      {"abutting", {box({5, 0, -10}, {8, 10, 0}), box({5, 0, 0}, {8, 10, 10}), kTarget}, kCell},
      {"staggered", {box({5, 0, -10}, {8, 10, 3}), box({10, 0, -3}, {13, 10, 10}), box({16, 1, -9}, {17, 2, 9})}, kCell},
      {"far walls", {box({100, 0, -40}, {102, 40, 2.6f}), box({104, 0, 0.6f}, {106, 40, 40}), box({120, 0, -8}, {121, 6, 8})}, kCell},
      {"grounded", {box({5, 0, -10}, {6, 4, 10}), box({7, 0, -1}, {8, 0.5f, 1})}, kCell},
      {"pillar", {box({3, 0, -1.5f}, {3.5f, 10, 1.5f}), box({4, 1, -0.2f}, {4.2f, 2, 0.2f})}, box({-2, 1, -2}, {2, 3, 2})},
  };
  uint64_t seed = 50;
  for (const Case& c : cases) {
    std::vector<Object> objects;
    for (const Aabb& b : c.boxes) objects.push_back(object_of(ObjectId(objects.size()), test::double_sided(box_mesh(b))));
    const Scene two_sided(objects);
    expect_keeps_what_rays_see(two_sided, c.cell, ++seed, 60, c.name);
    EXPECT_EQ(two_sided.visible(c.cell), Scene(boxes(c.boxes)).visible(c.cell)) << c.name;
  }
}

// A building of parts: a body, floor slabs through it, window boxes half sunk into a wall.
Mesh building(const Vec3& at, const Vec3& size) {
  Mesh m = box_mesh(box(at, at + size));
  for (float y = 3; y < size.y; y += 3)
    append(m, box_mesh(box({at.x - 0.2f, at.y + y, at.z - 0.2f}, {at.x + size.x + 0.2f, at.y + y + 0.3f, at.z + size.z + 0.2f})));
  for (float y = 1; y + 1.5f < size.y; y += 3)
    append(m, box_mesh(box({at.x + 0.5f, at.y + y, at.z - 0.1f}, {at.x + 1.5f, at.y + y + 1.5f, at.z + 0.1f})));
  return m;
}

// A random world of boxes (on the ground and floating, overlapping at times), buildings of
// parts and a few simplified bunnies; with `two_sided`, every mesh written double-sided.
std::vector<Object> random_world(uint64_t seed, const Mesh& bunny, bool two_sided = false) {
  Random rng(seed);
  std::vector<Object> out;
  for (int i = 0; i < 34; ++i) {
    const Vec3 c(rng.uniform(-28, 28), 0, rng.uniform(-28, 28));
    const Vec3 half(rng.uniform(0.3, 6), rng.uniform(0.5, 8), rng.uniform(0.3, 6));
    const float base = rng.uniform() < 0.2 ? float(rng.uniform(0.5, 4)) : 0.0f;
    out.push_back(object_of(ObjectId(out.size()),
                            box_mesh(box({c.x - half.x, base, c.z - half.z},
                                         {c.x + half.x, base + 2 * half.y, c.z + half.z}))));
  }
  for (int i = 0; i < 4; ++i) {
    const Vec3 at(rng.uniform(-28, 24), 0, rng.uniform(-28, 24));
    out.push_back(object_of(ObjectId(out.size()),
                            building(at, Vec3(rng.uniform(2, 6), rng.uniform(4, 14), rng.uniform(2, 6)))));
  }
  for (int i = 0; i < 3; ++i) {
    Mesh m = bunny;
    const Vec3 at(rng.uniform(-25, 25), 0, rng.uniform(-25, 25));
    transform(m, glm::translate(Mat4(1.0f), at) * glm::scale(Mat4(1.0f), Vec3(float(rng.uniform(3, 7)))));
    out.push_back(object_of(ObjectId(out.size()), std::move(m)));
  }
  if (two_sided)
    for (Object& o : out) o.mesh = test::double_sided(o.mesh);
  return out;
}

Mesh small_bunny() {
  Mesh m = import_model(test::cgal_mesh("bunny00.off")).objects[0].mesh;
  const Aabb b = bounds_of(m);
  const float scale = 1.0f / std::max({b.size().x, b.size().y, b.size().z});
  transform(m, glm::scale(Mat4(1.0f), Vec3(scale)) *
                   glm::translate(Mat4(1.0f), Vec3(-b.center().x, -b.min.y, -b.center().z)));
  const LodChain chain = build_lod_chain(m);
  for (const LodLevel& level : chain.levels)
    if (level.triangle_count <= 1500) return level.mesh;
  return chain.levels.back().mesh;
}

// THE ORACLE: recall must be 100 %; tightness is reported.
void oracle_never_misses(uint64_t first_seed, uint64_t last_seed, bool two_sided) {
  const Mesh bunny = small_bunny();
  size_t sampled = 0, reported_default = 0, reported_shrink = 0, reported_corner = 0, cells = 0;
  for (uint64_t seed = first_seed; seed <= last_seed; ++seed) {
    Scene scene(random_world(seed, bunny, two_sided));
    RayOracle oracle(*scene.world);
    const auto full = make_conservative_engine(*scene.world, {});
    const auto shrink = make_conservative_engine(*scene.world, only_shrinking());
    const auto corner = make_conservative_engine(*scene.world, only_corners());
    Random rng(seed * 1000);
    for (int c = 0; c < 6; ++c, ++cells) {
      const Vec3 centre(rng.uniform(-25, 25), rng.uniform(1, 4), rng.uniform(-25, 25));
      const Vec3 half(rng.uniform(0.5, 2.5), rng.uniform(0.5, 1.5), rng.uniform(0.5, 2.5));
      const ViewCell cell{CellId(c), {centre - half, centre + half}, 0, false};
      const std::set<ObjectId> seen = oracle.visible(cell.box, rng, 200, 12);
      for (const auto* engine : {full.get(), shrink.get(), corner.get()}) {
        const std::vector<ObjectId> set = engine->compute(cell).objects;
        ASSERT_TRUE(std::is_sorted(set.begin(), set.end()));
        for (ObjectId id : seen)
          EXPECT_TRUE(std::binary_search(set.begin(), set.end(), id))
              << "world " << seed << " cell " << c << " misses object " << id;
      }
      sampled += seen.size();
      reported_default += full->compute(cell).objects.size();
      reported_shrink += shrink->compute(cell).objects.size();
      reported_corner += corner->compute(cell).objects.size();
    }
  }
  std::printf("oracle%s: %zu cells, sampled visible %zu; tightness (set / sampled): default %.3f, "
              "shrinking only %.3f, corners only %.3f\n",
              two_sided ? " (double-sided)" : "", cells, sampled, double(reported_default) / sampled, double(reported_shrink) / sampled,
              double(reported_corner) / sampled);
}


TEST(ConservativeEngine, OracleNeverMissesASampledVisibleObject) { oracle_never_misses(1, 4, false); }

// The same worlds written double-sided, as some exporters write every mesh.
TEST(ConservativeEngine, OracleNeverMissesOnDoubleSidedWorlds) { oracle_never_misses(5, 6, true); }

}  // namespace
}  // namespace cellwalk
