// Seed 004 (Zheng) §3.2–§3.4 offline: the progressive mesh, the three vsplit DAGs and their
// attributes, each checked against a brute-force oracle (digest §7.5's invariants).
#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <map>
#include <numbers>
#include <random>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/systems/vdr/cut_state.hpp"
#include "cellwalk/systems/vdr/progressive_mesh.hpp"
#include "cellwalk/systems/vdr/selective_mesh.hpp"
#include "cellwalk/systems/vdr/vsplit_dag.hpp"
#include "lod/surface_distance.hpp"
#include "test_support.hpp"

namespace cellwalk::vdr {
namespace {

using Tri = std::array<uint32_t, 3>;

// A triangle turned so that its smallest corner comes first: orientation kept, start forgotten.
Tri canonical(Tri t) {
  std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  return t;
}

std::vector<Tri> canonical_triangles(std::span<const uint32_t> indices) {
  std::vector<Tri> out;
  for (size_t k = 0; k + 2 < indices.size(); k += 3) out.push_back(canonical({indices[k], indices[k + 1], indices[k + 2]}));
  std::sort(out.begin(), out.end());
  return out;
}

Mesh load_cgal(const std::string& name) { return import_model(test::cgal_mesh(name)).objects[0].mesh; }

// The input's triangles as corner positions, through a map from position to the PM's vertex id.
std::vector<Tri> input_triangles_as_pm_ids(const Mesh& input, const ProgressiveMesh& pm) {
  std::map<std::array<float, 3>, uint32_t> id;
  for (uint32_t v = 0; v < pm.vertex_count(); ++v) id[{pm.positions[v].x, pm.positions[v].y, pm.positions[v].z}] = v;
  std::vector<uint32_t> indices;
  for (uint32_t v : input.indices) {
    const Vec3 p = input.positions[v];
    const auto it = id.find({p.x, p.y, p.z});
    indices.push_back(it == id.end() ? kNone : it->second);
  }
  return canonical_triangles(indices);
}

TEST(ProgressiveMesh, AllSplitsGiveTheInputBackAndNoneTheBase) {
  for (const char* name : {"cow.off", "bunny00.off"}) {
    SCOPED_TRACE(name);
    const Mesh input = load_cgal(name);
    const ProgressiveMesh pm = build_progressive_mesh(input, {.base_triangles = 200}, name);
    ASSERT_GT(pm.vsplit_count(), 1000u);
    EXPECT_LE(pm.base_triangle_count, 202u);
    EXPECT_EQ(pm.vertex_count(), pm.base_vertex_count + pm.vsplit_count());
    const Mesh full = mesh_with_splits(pm, std::vector<bool>(pm.vsplit_count(), true));
    EXPECT_EQ(canonical_triangles(full.indices), input_triangles_as_pm_ids(input, pm));
    const Mesh base = mesh_with_splits(pm, std::vector<bool>(pm.vsplit_count(), false));
    EXPECT_EQ(canonical_triangles(base.indices), canonical_triangles(pm.base_indices));
  }
}

// Every prefix of the vsplit sequence is a level of the PM: edge-manifold, consistently
// oriented, without degenerate triangles, and each vsplit turns no adjusted face by > 90°.
TEST(ProgressiveMesh, EveryLevelIsManifoldAndNoSplitFoldsAFace) {
  const Mesh input = load_cgal("cow.off");
  const ProgressiveMesh pm = build_progressive_mesh(input, {.base_triangles = 100}, "cow");
  std::vector<bool> split(pm.vsplit_count(), false);
  for (uint32_t i = 0; i < pm.vsplit_count(); ++i) {
    split[i] = true;
    if (i % 97 != 0 && i + 1 != pm.vsplit_count()) continue;  // a sample of levels, and the last
    const Mesh after = mesh_with_splits(pm, split);
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t k = 0; k < after.indices.size(); k += 3)
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = after.indices[k + e], b = after.indices[k + (e + 1) % 3];
        ASSERT_NE(a, b) << "degenerate triangle after vsplit " << i;
        ASSERT_EQ(++directed[std::pair(a, b)], 1) << "edge used twice the same way after vsplit " << i;
      }
  }
  // Fold-over: replay with the slot table, comparing each adjusted face's normal.
  std::vector<Tri> slots(pm.triangle_slots(), Tri{kNone, kNone, kNone});
  for (uint32_t t = 0; t < pm.base_triangle_count; ++t)
    slots[t] = {pm.base_indices[3 * t], pm.base_indices[3 * t + 1], pm.base_indices[3 * t + 2]};
  const auto face_normal = [&](const Tri& t) {
    return glm::cross(pm.positions[t[1]] - pm.positions[t[0]], pm.positions[t[2]] - pm.positions[t[0]]);
  };
  for (uint32_t i = 0; i < pm.vsplit_count(); ++i) {
    for (uint32_t t : pm.adjusted_of(i)) {
      const Vec3 before = face_normal(slots[t]);
      for (uint32_t& v : slots[t])
        if (v == pm.v_p[i]) v = pm.v_c(i);
      EXPECT_GT(glm::dot(before, face_normal(slots[t])), 0.0f) << "vsplit " << i << " folds triangle " << t;
    }
    if (pm.v_l[i] != kNone) slots[pm.f_l(i)] = {pm.v_p[i], pm.v_c(i), pm.v_l[i]};
    if (pm.v_r[i] != kNone) slots[pm.f_r(i)] = {pm.v_c(i), pm.v_p[i], pm.v_r[i]};
  }
}

// The largest distance from the input's vertices to a simplified mesh, and back: the two-sided
// vertex Hausdorff distance a level's error is judged by.
float two_sided_distance(const Mesh& input, std::span<const Vec3> positions, std::span<const uint32_t> indices) {
  const TriangleGrid simplified(positions, indices);
  const TriangleGrid original(input.positions, input.indices);
  std::vector<Vec3> used;
  for (uint32_t v : indices) used.push_back(positions[v]);
  return std::sqrt(std::max(max_nearest2(simplified, input.positions, 0), max_nearest2(original, used, 0)));
}

// The cross-check: at the triangle count meshoptimizer reaches, the PM's level is as
// close to the input as meshoptimizer's simplification (both collapse onto existing vertices).
TEST(ProgressiveMesh, LevelsAreAsCloseAsMeshoptimizersAtTheSameTriangleCount) {
  for (const char* name : {"cow.off", "bunny00.off"}) {
    SCOPED_TRACE(name);
    const Mesh input = load_cgal(name);
    const ProgressiveMesh pm = build_progressive_mesh(input, {.base_triangles = 100}, name);
    for (double share : {0.25, 0.05}) {
      std::vector<uint32_t> simplified(input.indices.size());
      simplified.resize(meshopt_simplify(simplified.data(), input.indices.data(), input.indices.size(),
                                         &input.positions[0].x, input.positions.size(), sizeof(Vec3),
                                         size_t(input.indices.size() * share) / 3 * 3, 1.0f));
      const uint32_t target = static_cast<uint32_t>(simplified.size() / 3);
      std::vector<bool> split(pm.vsplit_count(), false);
      Mesh level = mesh_with_splits(pm, split);
      for (uint32_t i = 0; i < pm.vsplit_count() && level.triangle_count() < target; ++i) {
        split[i] = true;
        level.indices.resize(level.indices.size() + 3 * ((pm.v_l[i] != kNone) + (pm.v_r[i] != kNone)));
      }
      level = mesh_with_splits(pm, split);
      EXPECT_NEAR(double(level.triangle_count()), double(target), 2.0);
      const float ours = two_sided_distance(input, pm.positions, level.indices);
      const float theirs = two_sided_distance(input, input.positions, simplified);
      RecordProperty(std::string(name) + "_" + std::to_string(target) + "_pm_over_meshopt", std::to_string(ours / theirs));
      EXPECT_LE(ours, 2.0f * theirs) << "PM " << ours << " against meshoptimizer " << theirs << " at " << target << " triangles";
    }
  }
}

// Ancestor sets by brute force over the full DAG's edges (which are the potential parents).
std::vector<std::vector<bool>> ancestors(const VsplitDag& dag) {
  const uint32_t n = dag.node_count();
  std::vector<std::vector<bool>> up(n, std::vector<bool>(n, false));
  for (uint32_t t = 0; t < n; ++t)
    for (uint32_t p : dag.parents(t)) {
      up[t][p] = true;
      for (uint32_t a = 0; a < p; ++a)
        if (up[p][a]) up[t][a] = true;
    }
  return up;
}

TEST(VsplitDag, TheThreeBuildersKeepAncestryAndNonIsTheTransitiveReduction) {
  const ProgressiveMesh pm = build_progressive_mesh(load_cgal("cow.off"), {.base_triangles = 100}, "cow");
  const VsplitDag full = build_vsplit_dag(pm, DagKind::kFull);
  const VsplitDag non = build_vsplit_dag(pm, DagKind::kNonRedundant);
  const VsplitDag mini = build_vsplit_dag(pm, DagKind::kMiniRedundant);
  const auto closure = ancestors(full);
  std::vector<uint32_t> potential;
  for (const VsplitDag* dag : {&full, &non, &mini}) {
    SCOPED_TRACE(dag_kind_name(dag->kind));
    ASSERT_EQ(dag->node_count(), pm.vsplit_count());
    EXPECT_EQ(ancestors(*dag), closure);  // every potential parent is still an ancestor
    for (uint32_t t = 0; t < dag->node_count(); ++t) {
      for (uint32_t p : dag->parents(t)) ASSERT_LT(p, t);
      for (uint32_t d : dag->children(t)) ASSERT_GT(d, t);
    }
  }
  // non: exactly the edges p -> t with no other path from p to t.
  for (uint32_t t = 0; t < full.node_count(); ++t) {
    std::vector<uint32_t> reduced;
    for (uint32_t p : full.parents(t)) {
      bool implied = false;
      for (uint32_t q : full.parents(t)) implied |= q != p && closure[q][p];
      if (!implied) reduced.push_back(p);
    }
    const auto got = non.parents(t);
    ASSERT_EQ(std::vector<uint32_t>(got.begin(), got.end()), reduced) << "node " << t;
  }
  // Table 3.2's shape: full > mini > non, and mini removes most of the redundant edges.
  EXPECT_GT(full.edge_count(), mini.edge_count());
  EXPECT_GT(mini.edge_count(), non.edge_count());
  const double efficiency = double(full.edge_count() - mini.edge_count()) / double(full.edge_count() - non.edge_count());
  RecordProperty("mini_efficiency", std::to_string(efficiency));
  EXPECT_GT(efficiency, 0.6);
}

// §3.4: each node's sphere holds every vertex it or a descendant touches, its cone every normal
// of theirs, and its ap_err bounds their errors.
TEST(VsplitDag, AttributesBoundEveryDescendant) {
  const ProgressiveMesh pm = build_progressive_mesh(load_cgal("cow.off"), {.base_triangles = 100}, "cow");
  const VsplitDag dag = build_vsplit_dag(pm, DagKind::kMiniRedundant);
  const auto up = ancestors(dag);
  const NodeAttributes& a = dag.attributes;
  for (uint32_t i = 0; i < dag.node_count(); i += 7) {
    const Vec3 c = pm.positions[pm.v_c(i)], axis = pm.normals[pm.v_c(i)];
    const double theta = a.cone_sin[i] >= 1.0f ? std::numbers::pi : std::asin(double(a.cone_sin[i]));
    for (uint32_t d = i; d < dag.node_count(); ++d) {
      if (d != i && !up[d][i]) continue;
      EXPECT_GE(a.ap_err[i], pm.error[d]);
      for (uint32_t v : {pm.v_c(d), pm.v_p[d], pm.v_l[d], pm.v_r[d]})
        if (v != kNone) {
          EXPECT_LE(glm::distance(c, pm.positions[v]), a.rad[i] * 1.0001f + 1e-6f) << i << " -> " << d;
        }
      const double off = std::acos(std::clamp(double(glm::dot(glm::normalize(axis), glm::normalize(pm.normals[pm.v_c(d)]))), -1.0, 1.0));
      EXPECT_LE(off, theta + 1e-4) << "normal of " << d << " outside the cone of " << i;
    }
  }
}

std::vector<Tri> canonical(const std::vector<Tri>& triangles) {
  std::vector<Tri> out;
  for (const Tri& t : triangles) out.push_back(canonical(t));
  std::sort(out.begin(), out.end());
  return out;
}

VsplitOp op_of(const ProgressiveMesh& pm, uint32_t i) {
  return {i, pm.v_p[i], pm.v_l[i], pm.v_r[i], pm.positions[pm.v_c(i)], pm.normals[pm.v_c(i)], pm.adjusted_of(i)};
}

// §7.5 "consistency": any sequence of splits and collapses the counters allow leaves the
// client's selective mesh equal to the oracle's mesh of the same split set, for every DAG kind;
// and the counters equal a recount.
TEST(VsplitDag, RandomLegalCutsKeepTheSelectiveMeshEqualToTheOracle) {
  const ProgressiveMesh pm = build_progressive_mesh(load_cgal("cow.off"), {.base_triangles = 100}, "cow");
  for (DagKind kind : {DagKind::kFull, DagKind::kNonRedundant, DagKind::kMiniRedundant}) {
    SCOPED_TRACE(dag_kind_name(kind));
    const VsplitDag dag = build_vsplit_dag(pm, kind);
    CutState cut(dag);
    SelectiveMesh mesh(std::span(pm.positions).first(pm.base_vertex_count), std::span(pm.normals).first(pm.base_vertex_count),
                       pm.base_indices);
    std::mt19937 rng(static_cast<uint32_t>(kind) + 7);
    std::vector<uint32_t> legal;
    for (int step = 0; step < 6000; ++step) {
      const bool refine = rng() % 100 < 70;  // drift towards finer cuts, collapsing on the way
      legal.clear();
      for (uint32_t k = 0; k < dag.node_count(); ++k)
        if (refine ? cut.can_split(k) : cut.can_collapse(k)) legal.push_back(k);
      if (legal.empty()) continue;
      const uint32_t i = legal[rng() % legal.size()];
      if (refine) {
        cut.split(i);
        mesh.vsplit(op_of(pm, i));
      } else {
        cut.collapse(i);
        mesh.ecol(op_of(pm, i));
      }
      if (step % 250 != 0) continue;
      std::vector<bool> split(dag.node_count());
      for (uint32_t k = 0; k < dag.node_count(); ++k) split[k] = cut.is_split(k);
      ASSERT_EQ(canonical(mesh.triangles_by_id()), canonical_triangles(mesh_with_splits(pm, split).indices)) << "step " << step;
      for (uint32_t k = 0; k < dag.node_count(); ++k) {
        uint32_t expected = 0;
        if (split[k])
          for (uint32_t d : dag.children(k)) expected += split[d];
        else
          for (uint32_t p : dag.parents(k)) expected += !split[p];
        ASSERT_EQ(cut.counter(k), expected) << "node " << k;
      }
    }
    EXPECT_GT(cut.split_count(), dag.node_count() / 4);
  }
}

TEST(SelectiveMesh, RefusesAnOpOutOfStepAndStaysAsItWas) {
  const ProgressiveMesh pm = build_progressive_mesh(load_cgal("cow.off"), {.base_triangles = 100}, "cow");
  SelectiveMesh mesh(std::span(pm.positions).first(pm.base_vertex_count), std::span(pm.normals).first(pm.base_vertex_count),
                     pm.base_indices);
  const auto before = mesh.triangles_by_id();
  // The last vsplit needs vertices later splits make; collapsing anything needs it split first.
  EXPECT_THROW(mesh.vsplit(op_of(pm, pm.vsplit_count() - 1)), Error);
  EXPECT_THROW(mesh.ecol(op_of(pm, 0)), Error);
  VsplitOp wrong = op_of(pm, 0);
  std::vector<uint32_t> twice(wrong.adjusted.begin(), wrong.adjusted.end());
  twice.push_back(twice.empty() ? 0 : twice.front());
  wrong.adjusted = twice;
  EXPECT_THROW(mesh.vsplit(wrong), Error);
  EXPECT_EQ(mesh.triangles_by_id(), before);
  mesh.vsplit(op_of(pm, 0));
  EXPECT_THROW(mesh.vsplit(op_of(pm, 0)), Error);
  mesh.ecol(op_of(pm, 0));
  EXPECT_EQ(canonical(mesh.triangles_by_id()), canonical(before));
  EXPECT_GT(mesh.aux_bytes(), 0u);
  EXPECT_GT(mesh.render_bytes(), 0u);
}

}  // namespace
}  // namespace cellwalk::vdr
