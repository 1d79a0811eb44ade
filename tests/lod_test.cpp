// Tests of the LOD chains (src/lod/lod_chain.cpp): chain shape on the bunny, the recorded
// error against a brute-force geometric oracle, cache and fetch order, the sloppy fallback,
// and the choice of a level by pixel error.
#include "cellwalk/lod.hpp"

#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>

#include "cellwalk/import.hpp"
#include "cellwalk/screen_error.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

const Mesh& bunny() {
  static const Mesh mesh = import_model(test::cgal_mesh("bunny00.off")).at(0).mesh;
  return mesh;
}

const LodChain& bunny_chain() {
  static const LodChain chain = build_lod_chain(bunny());
  return chain;
}

using Triangle = std::array<std::array<float, 3>, 3>;

// Each triangle by its corner positions, rotated so the smallest corner comes first (the
// winding is kept), as a sorted multiset.
std::vector<Triangle> triangle_set(const Mesh& m) {
  std::vector<Triangle> out;
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    Triangle tri;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = m.positions[m.indices[t + k]];
      tri[k] = {p.x, p.y, p.z};
    }
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The oracle: distance from p to triangle abc by projecting onto the plane when the foot is
// inside, else the nearest of the three edges as segments (a different method from the
// library's Voronoi-region walk).
float segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const float len2 = glm::dot(ab, ab);
  const float t = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  return glm::length(p - (a + t * ab));
}

float triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = glm::cross(b - a, c - a);
  const float n2 = glm::dot(n, n);
  if (n2 > 0) {
    const Vec3 foot = p - n * (glm::dot(p - a, n) / n2);
    const bool inside = glm::dot(glm::cross(b - a, foot - a), n) >= 0 &&
                        glm::dot(glm::cross(c - b, foot - b), n) >= 0 &&
                        glm::dot(glm::cross(a - c, foot - c), n) >= 0;
    if (inside) return glm::length(p - foot);
  }
  return std::min(
      {segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}

// Max over `samples` random original vertices of the distance to the nearest level triangle.
// Brute force, skipping triangles whose bounding sphere is farther than the best so far.
float measured_error(const Mesh& original, const Mesh& level, size_t samples) {
  std::vector<Vec3> centre;
  std::vector<float> radius;
  for (size_t t = 0; t < level.indices.size(); t += 3) {
    const Vec3 &a = level.positions[level.indices[t]], &b = level.positions[level.indices[t + 1]],
               &c = level.positions[level.indices[t + 2]];
    centre.push_back((a + b + c) / 3.0f);
    radius.push_back(std::max({glm::length(a - centre.back()), glm::length(b - centre.back()),
                               glm::length(c - centre.back())}));
  }
  std::mt19937 rng(7);
  std::uniform_int_distribution<size_t> pick(0, original.vertex_count() - 1);
  float worst = 0;
  for (size_t s = 0; s < samples; ++s) {
    const Vec3& p = original.positions[pick(rng)];
    float best = std::numeric_limits<float>::infinity();
    for (size_t t = 0; t < centre.size(); ++t) {
      if (glm::length(p - centre[t]) - radius[t] >= best) continue;
      best = std::min(best, triangle_distance(p, level.positions[level.indices[3 * t]],
                                              level.positions[level.indices[3 * t + 1]],
                                              level.positions[level.indices[3 * t + 2]]));
    }
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(LodChain, BunnyChainShape) {
  const LodChain& chain = bunny_chain();
  ASSERT_GE(chain.levels.size(), 8u);  // 75k triangles halved down to 32 is ~11 levels
  EXPECT_EQ(chain.levels[0].error, 0.0f);
  EXPECT_EQ(chain.levels[0].method, LodMethod::kOriginal);
  for (size_t i = 0; i < chain.levels.size(); ++i) {
    const LodLevel& level = chain.levels[i];
    SCOPED_TRACE("level " + std::to_string(i));
    EXPECT_NO_THROW(validate(level.mesh, "level"));
    EXPECT_EQ(level.triangle_count, level.mesh.triangle_count());
    EXPECT_EQ(level.mesh.normals.size(), level.mesh.vertex_count());
    if (i == 0) continue;
    const LodLevel& previous = chain.levels[i - 1];
    EXPECT_LT(level.triangle_count, previous.triangle_count);
    EXPECT_GE(level.error, previous.error);
    EXPECT_GT(level.error, 0.0f);
    // ratio 0.5 unless a stall was taken over by the sloppy simplifier
    EXPECT_LE(level.triangle_count, previous.triangle_count * 0.9 + 1);
  }
  EXPECT_LE(chain.levels.back().triangle_count, 2 * LodParams{}.min_triangles);
}

TEST(LodChain, LevelZeroIsTheInput) {
  const Mesh& level0 = bunny_chain().levels[0].mesh;
  EXPECT_EQ(level0.vertex_count(), bunny().vertex_count());
  EXPECT_EQ(triangle_set(level0), triangle_set(bunny()));
}

// The claim behind LodLevel::error, checked by brute force on 2,000 original vertices.
// What was found to hold (printed): meshopt's quadric error underestimates the distance:
// measured / recorded reaches 2.04 on the bunny (1.18..2.04 over the levels), so 1.5 does
// not hold; the assertion is 2.5 and docs/lod.md says what it means for a pixel bound.
TEST(LodChain, RecordedErrorBoundsMeasuredDistance) {
  const LodChain& chain = bunny_chain();
  const float extent = glm::length(bounds_of(bunny()).size());
  for (size_t i = 1; i < chain.levels.size(); ++i) {
    const LodLevel& level = chain.levels[i];
    const float measured = measured_error(bunny(), level.mesh, 2000);
    std::printf("level %2zu: %6zu triangles, recorded %.5f, measured %.5f, ratio %.2f\n", i,
                level.triangle_count, level.error, measured, measured / level.error);
    EXPECT_LE(measured, level.error * 2.5f + 1e-5f * extent) << "level " << i;
  }
}

// Vertex-fetch order: vertices appear in the index buffer in the order they are stored.
// Vertex-cache order: far fewer cache misses than the same triangles shuffled.
TEST(LodChain, LevelsAreCacheAndFetchOptimised) {
  for (const LodLevel& level : bunny_chain().levels) {
    const Mesh& m = level.mesh;
    uint32_t next = 0;
    for (uint32_t i : m.indices) {
      ASSERT_LE(i, next);
      if (i == next) ++next;
    }
    EXPECT_EQ(next, m.vertex_count());  // compacted: every vertex is used
    std::vector<uint32_t> shuffled = m.indices;
    std::vector<size_t> order(shuffled.size() / 3);
    for (size_t t = 0; t < order.size(); ++t) order[t] = t;
    std::shuffle(order.begin(), order.end(), std::mt19937(1));
    for (size_t t = 0; t < order.size(); ++t) {
      std::copy_n(&m.indices[order[t] * 3], 3, &shuffled[t * 3]);
    }
    const float acmr =
        meshopt_analyzeVertexCache(m.indices.data(), m.indices.size(), m.vertex_count(), 16, 0, 0)
            .acmr;
    const float shuffled_acmr =
        meshopt_analyzeVertexCache(shuffled.data(), shuffled.size(), m.vertex_count(), 16, 0, 0)
            .acmr;
    if (m.triangle_count() > 1000) {
      EXPECT_LT(acmr, 0.75f * shuffled_acmr);
    }
  }
}

// A triangle soup (a wavy 48×48 grid whose triangles share no vertex): every edge is a
// border, so the topology-preserving simplifier stalls and the sloppy one, which welds by
// position, must take over.
TEST(LodChain, StallFallsBackToSloppyWithMeasuredError) {
  Mesh soup;
  auto height = [](int x, int z) { return 0.5f * std::sin(x * 0.3f) * std::cos(z * 0.2f); };
  for (int z = 0; z < 48; ++z) {
    for (int x = 0; x < 48; ++x) {
      const Vec3 p00(x, height(x, z), z), p10(x + 1, height(x + 1, z), z),
          p01(x, height(x, z + 1), z + 1), p11(x + 1, height(x + 1, z + 1), z + 1);
      for (const Vec3& p : {p00, p01, p10, p10, p01, p11}) {
        soup.indices.push_back(uint32_t(soup.positions.size()));
        soup.positions.push_back(p);
      }
    }
  }
  const LodChain chain = build_lod_chain(soup);
  ASSERT_GE(chain.levels.size(), 2u);
  bool sloppy = false;
  for (size_t i = 1; i < chain.levels.size(); ++i) {
    const LodLevel& level = chain.levels[i];
    sloppy = sloppy || level.method == LodMethod::kSloppy;
    EXPECT_LT(level.triangle_count, chain.levels[i - 1].triangle_count);
    EXPECT_GE(level.error, chain.levels[i - 1].error);
    if (level.method == LodMethod::kSloppy) {
      EXPECT_LE(measured_error(soup, level.mesh, 500), level.error * 1.5f + 1e-4f);
    }
  }
  EXPECT_TRUE(sloppy);
}

TEST(LodChain, SmallMeshIsOneLevel) {
  const Mesh box = test::box_mesh({Vec3(0), Vec3(1)});
  const LodChain chain = build_lod_chain(box);
  ASSERT_EQ(chain.levels.size(), 1u);
  EXPECT_EQ(triangle_set(chain.levels[0].mesh), triangle_set(box));
  EXPECT_EQ(build_lod_chain(Mesh{}).levels.size(), 1u);
}

LodChain chain_with_errors(std::initializer_list<float> errors) {
  LodChain chain;
  for (float e : errors) chain.levels.push_back({Mesh{}, 0, e, LodMethod::kSimplify});
  return chain;
}

TEST(LodSelect, CoarsestLevelUnderTheBound) {
  const LodChain chain = chain_with_errors({0.0f, 1.0f, 2.0f, 4.0f});
  EXPECT_EQ(select_level(chain, 0.5f, 1.0f), 2u);   // 2 · 0.5 = 1 ≤ 1, 4 · 0.5 > 1
  EXPECT_EQ(select_level(chain, 0.25f, 1.0f), 3u);  // everything fits: the coarsest
  EXPECT_EQ(select_level(chain, 2.0f, 1.0f), 0u);   // 1 · 2 > 1: only the original
  EXPECT_EQ(select_level(chain, std::numeric_limits<float>::infinity(), 1.0f), 0u);
  EXPECT_EQ(select_level(chain, 0.0f, 0.5f), 3u);
}

// Farther viewpoints never select a finer level, and the selected level's projected error
// from that viewpoint is under the bound.
TEST(LodSelect, BunnyLevelsCoarsenWithDistance) {
  const LodChain& chain = bunny_chain();
  const Lens lens;
  const Aabb box = bounds_of(bunny());
  size_t last = 0;
  for (float d = 0.0f; d < 300.0f; d += 0.05f) {
    const float ppu = pixels_per_unit(d, lens);
    const size_t i = select_level(chain, ppu, 1.0f);
    EXPECT_GE(i, last);
    EXPECT_LE(screen_space_error(chain.levels[i].error, d, lens), 1.0f);
    last = i;
  }
  EXPECT_EQ(last, chain.levels.size() - 1);
  EXPECT_EQ(select_level(chain, pixels_per_unit(distance_to_box(box.center(), box), lens), 1.0f),
            0u);
}

}  // namespace
}  // namespace cellwalk
