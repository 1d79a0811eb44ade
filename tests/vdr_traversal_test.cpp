// Seed 004 (Zheng) §3.4 view tests and §4.3–§4.4 traversals, against brute-force oracles: the
// out-of-view test never drops a node with anything in view, a converged cut needs nothing more,
// and along the thesis's paths the client's mesh equals the oracle's, under N, the budget and
// the 64 KB batch.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>

#include "cellwalk/scene/import.hpp"
#include "cellwalk/systems/vdr/selective_mesh.hpp"
#include "cellwalk/systems/vdr/traversal.hpp"
#include "cellwalk/systems/vdr/vdr_paths.hpp"
#include "test_support.hpp"

namespace cellwalk::vdr {
namespace {

VdrModel traversal_model(const char* name) {
  VdrModel m;
  m.pm = build_progressive_mesh(import_model(test::cgal_mesh(name)).objects[0].mesh, {.base_triangles = 200}, name);
  m.dag = build_vsplit_dag(m.pm, DagKind::kMiniRedundant);
  for (const Vec3& p : m.pm.positions) m.bounds.extend(p);
  return m;
}

const VdrModel& bunny() {
  static const VdrModel m = traversal_model("bunny00.off");
  return m;
}

// Every node and its descendants, by a walk down the out-edges.
std::vector<uint32_t> subtree(const VsplitDag& dag, uint32_t root) {
  std::vector<uint32_t> out{root}, seen;
  std::vector<bool> mark(dag.node_count(), false);
  mark[root] = true;
  for (size_t k = 0; k < out.size(); ++k)
    for (uint32_t d : dag.children(out[k]))
      if (!mark[d]) mark[d] = true, out.push_back(d);
  return out;
}

ViewParams random_view(std::mt19937& rng, const Aabb& box) {
  std::uniform_real_distribution<float> u(-1, 1);
  const Vec3 c = box.center();
  const float r = glm::length(box.size()) / 2;
  ViewParams vp;
  vp.eye = c + Vec3(u(rng), u(rng), u(rng)) * 2.0f * r;
  vp.aim = c + Vec3(u(rng), u(rng), u(rng)) * r;
  vp.alpha = 0.3f + 0.5f * (u(rng) + 1);
  return vp;
}

// With the normal cones opened (sin θ = 1: never back-facing), need 0 means out of view: then
// no vertex of the node or a descendant may lie inside the view cone.
TEST(VdrViewTests, OutOfViewNeverDropsAVertexInTheViewCone) {
  VdrModel open = bunny();
  std::fill(open.dag.attributes.cone_sin.begin(), open.dag.attributes.cone_sin.end(), 1.0f);
  const Traversal t(open, TraversalKind::kPriority);
  const ProgressiveMesh& pm = open.pm;
  std::mt19937 rng(11);
  uint32_t culled = 0;
  for (int view = 0; view < 20; ++view) {
    const ViewParams vp = random_view(rng, open.bounds);
    const Vec3 dir = glm::normalize(vp.aim - vp.eye);
    for (uint32_t i = 0; i < open.dag.node_count(); i += 13) {
      if (t.need(i, vp) != 0) continue;
      ++culled;
      for (uint32_t d : subtree(open.dag, i))
        for (uint32_t v : {pm.v_c(d), pm.v_p[d], pm.v_l[d], pm.v_r[d]}) {
          if (v == kNone) continue;
          const Vec3 to = pm.positions[v] - vp.eye;
          const float angle = std::acos(std::clamp(glm::dot(to, dir) / glm::length(to), -1.0f, 1.0f));
          ASSERT_GT(angle, vp.alpha - 1e-4f) << "node " << i << " culled with vertex " << v << " of " << d << " in view";
        }
    }
  }
  EXPECT_GT(culled, 1000u);  // the test saw the cull at work
}

// Eq. 3.4.1 is exact for the node's own faces (both hold v_c): a back-facing node's f_l and f_r
// face away from the eye.
TEST(VdrViewTests, BackFacingNodesOwnFacesFaceAway) {
  const VdrModel& m = bunny();
  const ProgressiveMesh& pm = m.pm;
  const Traversal t(m, TraversalKind::kPriority);
  std::mt19937 rng(12);
  uint32_t back = 0;
  for (int view = 0; view < 20; ++view) {
    ViewParams vp = random_view(rng, m.bounds);
    vp.alpha = std::numbers::pi_v<float>;  // a cone of everything: only the back-face test culls
    for (uint32_t i = 0; i < m.dag.node_count(); i += 5) {
      if (t.need(i, vp) != 0) continue;
      ++back;
      const Vec3 c = pm.positions[pm.v_c(i)], p = pm.positions[pm.v_p[i]];
      // The cosine between the face's normal and the view ray to v_c; float rounding of the
      // stored cone may put a face a hair past 90°, not more.
      const auto facing = [&](const Vec3& n) { return glm::dot(glm::normalize(n), glm::normalize(c - vp.eye)); };
      if (pm.v_l[i] != kNone) {
        EXPECT_GE(facing(glm::cross(c - p, pm.positions[pm.v_l[i]] - p)), -1e-4f) << "f_l of " << i;
      }
      if (pm.v_r[i] != kNone) {
        EXPECT_GE(facing(glm::cross(p - c, pm.positions[pm.v_r[i]] - c)), -1e-4f) << "f_r of " << i;
      }
    }
  }
  EXPECT_GT(back, 500u);
}

// Run to a fixed point with no limits: every node the cut could split needs nothing, and every
// node it could collapse needs to stay split — for each traversal.
TEST(VdrTraversal, ConvergedCutNeedsNothingMore) {
  const VdrModel& m = bunny();
  ViewParams vp;
  vp.eye = m.bounds.center() + Vec3(0, 0, 1.3f * glm::length(m.bounds.size()) / 2);
  vp.aim = m.bounds.center();
  vp.n = 100000;
  vp.tau = 0.002f;
  for (TraversalKind kind : {TraversalKind::kPriority, TraversalKind::kLinear, TraversalKind::kConstant}) {
    SCOPED_TRACE(traversal_name(kind));
    Traversal t(m, kind, ErrorUnits::kLength);
    std::vector<Op> ops;
    int frames = 0;
    do {
      ops.clear();
      t.manage(vp, ops, 1u << 30);
    } while (!ops.empty() && ++frames < 500);
    ASSERT_LT(frames, 500);
    EXPECT_GT(t.cut().split_count(), 1000u);
    for (uint32_t i = 0; i < m.dag.node_count(); ++i) {
      if (t.cut().can_split(i)) {
        ASSERT_LT(t.need(i, vp), 1.0f) << "node " << i << " still needs a split";
      }
      if (t.cut().can_collapse(i)) {
        ASSERT_GE(t.need(i, vp), 1.0f) << "node " << i << " still needs a collapse";
      }
    }
  }
}

using SlotTriangle = std::array<uint32_t, 3>;
std::vector<SlotTriangle> sorted_rotated(std::vector<SlotTriangle> ts) {
  for (auto& t : ts) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  std::sort(ts.begin(), ts.end());
  return ts;
}

// Along both thesis paths with the thesis's settings scaled to the bunny (B = 20k, N = 500):
// the client's selective mesh takes every batch and equals the oracle's mesh of the server's
// cut; the triangle count never passes B; no direction passes N; no batch passes 64 KB.
TEST(VdrTraversal, ClientStaysInStepUnderTheBudgetAlongThePaths) {
  const VdrModel& m = bunny();
  const ProgressiveMesh& pm = m.pm;
  constexpr uint32_t kBudget = 20000, kN = 500;
  for (TraversalKind kind : {TraversalKind::kPriority, TraversalKind::kLinear, TraversalKind::kConstant}) {
    for (int path : {1, 2}) {
      SCOPED_TRACE(traversal_name(kind) + " path " + std::to_string(path));
      Traversal t(m, kind, ErrorUnits::kLength);  // the bunny is 0.15 m: raw QE would ask for little
      SelectiveMesh mesh(std::span(pm.positions).first(pm.base_vertex_count), std::span(pm.normals).first(pm.base_vertex_count),
                         pm.base_indices);
      uint32_t frame = 0, most = 0;
      for (const VdrFrame& f : thesis_path(path, m.bounds)) {
        ViewParams vp{f.eye, f.aim, 0.55f, 0.001f, BudgetMode::kFree, kN};
        vp.mode = mesh.triangle_count() + 2 * kN <= kBudget ? BudgetMode::kFree : BudgetMode::kBudget;
        std::vector<Op> ops;
        const TraversalStats s = t.manage(vp, ops);
        ASSERT_LE(s.batch_bytes, 64u * 1024);
        if (kind == TraversalKind::kConstant) {
          ASSERT_LE(s.evaluated, 2 * kN);
        } else {
          ASSERT_TRUE(s.collapses <= kN && s.splits <= kN);
        }
        for (const Op& op : ops) {
          const VsplitOp v{op.node, pm.v_p[op.node], pm.v_l[op.node], pm.v_r[op.node], pm.positions[pm.v_c(op.node)],
                           pm.normals[pm.v_c(op.node)], pm.adjusted_of(op.node)};
          if (op.split) mesh.vsplit(v);
          else mesh.ecol(v);
        }
        ASSERT_EQ(mesh.triangle_count(), t.triangle_count());
        ASSERT_LE(mesh.triangle_count(), kBudget);
        most = std::max(most, mesh.triangle_count());
        if (++frame % 40 != 0) continue;
        std::vector<bool> split(m.dag.node_count());
        for (uint32_t i = 0; i < split.size(); ++i) split[i] = t.cut().is_split(i);
        const Mesh oracle = mesh_with_splits(pm, split);
        std::vector<SlotTriangle> expected;
        for (size_t k = 0; k < oracle.indices.size(); k += 3)
          expected.push_back({oracle.indices[k], oracle.indices[k + 1], oracle.indices[k + 2]});
        ASSERT_EQ(sorted_rotated(mesh.triangles_by_id()), sorted_rotated(expected)) << "frame " << frame;
      }
      EXPECT_GT(most, kBudget / 2);  // the budget was reached for, not idle
    }
  }
}

}  // namespace
}  // namespace cellwalk::vdr
