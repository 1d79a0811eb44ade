// Seed 004 (Zheng), §3.3: the vsplit DAG's three builders (Figs. 3.8–3.10), and §3.4: the
// bottom-up visibility attributes (digest §3.2–§3.3).
#include "cellwalk/systems/vdr/vsplit_dag.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "cellwalk/core/error.hpp"

namespace cellwalk::vdr {
namespace {

// Every node's potential parents, CSR, each list by decreasing id.
struct Potentials {
  std::vector<uint32_t> offsets{0}, ids;
  std::span<const uint32_t> of(uint32_t i) const { return {ids.data() + offsets[i], ids.data() + offsets[i + 1]}; }
};

Potentials all_potentials(const ProgressiveMesh& pm) {
  Potentials out;
  out.offsets.reserve(pm.vsplit_count() + 1);
  std::vector<uint32_t> p;
  for (uint32_t i = 0; i < pm.vsplit_count(); ++i) {
    potential_parents(pm, i, p);
    out.ids.insert(out.ids.end(), p.begin(), p.end());
    out.offsets.push_back(static_cast<uint32_t>(out.ids.size()));
  }
  return out;
}

// Fig. 3.9/3.10's loop over P by decreasing id: keep the largest left, then drop what `covered`
// says the kept one already implies. `kept` comes out by decreasing id.
template <typename Covered>
void reduce(std::span<const uint32_t> candidates, std::vector<uint32_t>& kept, Covered covered) {
  kept.clear();
  std::vector<uint8_t> dropped(candidates.size(), 0);
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (dropped[k]) continue;
    kept.push_back(candidates[k]);
    for (size_t j = k + 1; j < candidates.size(); ++j)
      if (!dropped[j] && covered(candidates[k], candidates[j])) dropped[j] = 1;
  }
}

class DagBuilder {
 public:
  DagBuilder(const ProgressiveMesh& pm, DagKind kind) : kind_(kind), potentials_(all_potentials(pm)) {
    dag_.kind = kind;
    dag_.in_offsets.reserve(pm.vsplit_count() + 1);
    if (kind == DagKind::kNonRedundant) visit_stamp_.assign(pm.vsplit_count(), 0);
  }

  VsplitDag run(const DagProgress& progress) {
    const uint32_t n = static_cast<uint32_t>(potentials_.offsets.size() - 1);
    std::vector<uint32_t> kept;
    for (uint32_t t = 0; t < n; ++t) {
      parents_of(t, kept);
      dag_.in_edges.insert(dag_.in_edges.end(), kept.rbegin(), kept.rend());  // increasing id
      dag_.in_offsets.push_back(static_cast<uint32_t>(dag_.in_edges.size()));
      if (progress && (t & 4095) == 0) progress(t, n);
    }
    derive_children(dag_);
    return std::move(dag_);
  }

 private:
  void parents_of(uint32_t t, std::vector<uint32_t>& kept) {
    const std::span<const uint32_t> p = potentials_.of(t);
    switch (kind_) {
      case DagKind::kFull:
        kept.assign(p.begin(), p.end());
        return;
      case DagKind::kMiniRedundant:
        // Fig. 3.10: p' is dropped when it is a potential parent (so an ancestor) of p_max.
        return reduce(p, kept, [&](uint32_t pmax, uint32_t other) {
          const auto g = potentials_.of(pmax);
          return std::binary_search(g.begin(), g.end(), other, std::greater<>());
        });
      case DagKind::kNonRedundant:
        // Fig. 3.9: p' is dropped when it is any ancestor of p_max. Ancestors of the kept nodes
        // are marked once per t (below the smallest candidate nothing matters).
        ++stamp_;
        return reduce(p, kept, [&](uint32_t pmax, uint32_t other) {
          mark_ancestors(pmax, p.back());
          return visit_stamp_[other] == stamp_;
        });
    }
  }

  // Marks every ancestor of `from` with id >= lo (the DAG so far keeps every ancestry).
  void mark_ancestors(uint32_t from, uint32_t lo) {
    if (marked_from_ == from && marked_stamp_ == stamp_) return;
    marked_from_ = from, marked_stamp_ = stamp_;
    stack_.assign(1, from);
    while (!stack_.empty()) {
      const uint32_t v = stack_.back();
      stack_.pop_back();
      for (uint32_t k = dag_.in_offsets[v]; k < dag_.in_offsets[v + 1]; ++k) {
        const uint32_t a = dag_.in_edges[k];
        if (a < lo || visit_stamp_[a] == stamp_) continue;
        visit_stamp_[a] = stamp_;
        stack_.push_back(a);
      }
    }
  }

  DagKind kind_;
  Potentials potentials_;
  VsplitDag dag_;
  std::vector<uint32_t> visit_stamp_, stack_;
  uint32_t stamp_ = 0, marked_from_ = kNone, marked_stamp_ = 0;
};

double angle_between(const Vec3& a, const Vec3& b) {
  const float la = glm::length(a), lb = glm::length(b);
  if (la == 0 || lb == 0) return std::numbers::pi / 2;
  return std::acos(std::clamp(double(glm::dot(a, b)) / (double(la) * lb), -1.0, 1.0));
}

}  // namespace

std::string dag_kind_name(DagKind kind) {
  switch (kind) {
    case DagKind::kFull: return "full";
    case DagKind::kNonRedundant: return "non";
    case DagKind::kMiniRedundant: return "mini";
  }
  return "?";
}

DagKind parse_dag_kind(const std::string& word) {
  for (DagKind k : {DagKind::kFull, DagKind::kNonRedundant, DagKind::kMiniRedundant})
    if (dag_kind_name(k) == word) return k;
  fail("--dag", "unknown DAG kind '" + word + "': use full, non or mini");
}

void derive_children(VsplitDag& dag) {
  const uint32_t n = dag.node_count();
  dag.out_offsets.assign(n + 1, 0);
  for (uint32_t a : dag.in_edges) ++dag.out_offsets[a + 1];
  for (uint32_t i = 0; i < n; ++i) dag.out_offsets[i + 1] += dag.out_offsets[i];
  dag.out_edges.resize(dag.in_edges.size());
  std::vector<uint32_t> fill(dag.out_offsets.begin(), dag.out_offsets.end() - 1);
  for (uint32_t t = 0; t < n; ++t)  // children come out by increasing id
    for (uint32_t a : dag.parents(t)) dag.out_edges[fill[a]++] = t;
}

uint64_t VsplitDag::byte_size() const {
  const uint64_t words = in_offsets.size() + in_edges.size() + out_offsets.size() + out_edges.size() +
                         attributes.rad.size() + attributes.cone_sin.size() + attributes.ap_err.size();
  return words * 4;
}

VsplitDag build_vsplit_dag(const ProgressiveMesh& pm, DagKind kind, const DagProgress& progress) {
  VsplitDag dag = DagBuilder(pm, kind).run(progress);
  dag.attributes = compute_attributes(pm, dag);
  return dag;
}

NodeAttributes compute_attributes(const ProgressiveMesh& pm, const VsplitDag& dag) {
  const uint32_t n = pm.vsplit_count();
  NodeAttributes a;
  a.rad.resize(n), a.cone_sin.resize(n), a.ap_err.resize(n);
  std::vector<double> theta(n);
  constexpr double kRight = std::numbers::pi / 2;
  for (uint32_t i = n; i-- > 0;) {
    const Vec3 c = pm.positions[pm.v_c(i)], p = pm.positions[pm.v_p[i]], nc = pm.normals[pm.v_c(i)];
    float rad = glm::distance(c, p);
    double th = 0;
    if (pm.v_l[i] != kNone) {
      const Vec3 l = pm.positions[pm.v_l[i]];
      rad = std::max(rad, glm::distance(c, l));
      th = std::max(th, angle_between(nc, glm::cross(c - p, l - p)));  // f_l = (v_p, v_c, v_l)
    }
    if (pm.v_r[i] != kNone) {
      const Vec3 r = pm.positions[pm.v_r[i]];
      rad = std::max(rad, glm::distance(c, r));
      th = std::max(th, angle_between(nc, glm::cross(p - c, r - c)));  // f_r = (v_c, v_p, v_r)
    }
    th = std::min(kRight, th);
    float err = pm.error[i];
    for (uint32_t d : dag.children(i)) {
      rad = std::max(rad, glm::distance(c, pm.positions[pm.v_c(d)]) + a.rad[d]);
      th = std::max(th, std::min(kRight, angle_between(nc, pm.normals[pm.v_c(d)]) + theta[d]));
      err = std::max(err, a.ap_err[d]);
    }
    a.rad[i] = rad;
    theta[i] = th;
    a.cone_sin[i] = static_cast<float>(std::sin(th));
    a.ap_err[i] = err;
  }
  return a;
}

}  // namespace cellwalk::vdr
