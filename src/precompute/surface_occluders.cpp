// Occluders from the world's surfaces: voxelisation, free components, boxes per component.
// Seeds: 001 vLOD §5.2.2 (solid convex occluders; a conservative stand-in for concave volume)
// and §5.3 (large occluders first). The argument: docs/surface-occluders.md.
#include "precompute/surface_occluders.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <numeric>
#include <string>

#include "cellwalk/core/error.hpp"

namespace cellwalk::visibility {
namespace {

// Doubt marks a voxel surface: each voxel is tested grown by this fraction of its edge.
constexpr double kMarginFraction = 1e-3;

// True unless `axis` separates the triangle (v relative to the box centre) from the box of
// half-extent `half`; a triangle touching the box counts as meeting it.
bool separates(const glm::dvec3& axis, const glm::dvec3 (&v)[3], const glm::dvec3& half) {
  const double p0 = glm::dot(axis, v[0]), p1 = glm::dot(axis, v[1]), p2 = glm::dot(axis, v[2]);
  const double r = half.x * std::abs(axis.x) + half.y * std::abs(axis.y) + half.z * std::abs(axis.z);
  return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
}

// Akenine-Möller's triangle–box test: the 3 box axes, the triangle's normal and the 9 cross
// products of box axes and triangle edges.
bool triangle_meets_box(const glm::dvec3 (&v)[3], const glm::dvec3& half) {
  for (int a = 0; a < 3; ++a) {
    glm::dvec3 axis(0.0);
    axis[a] = 1.0;
    if (separates(axis, v, half)) return false;
  }
  const glm::dvec3 edges[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  if (separates(glm::cross(edges[0], edges[1]), v, half)) return false;
  for (int a = 0; a < 3; ++a)
    for (const glm::dvec3& e : edges) {
      glm::dvec3 unit(0.0);
      unit[a] = 1.0;
      if (separates(glm::cross(unit, e), v, half)) return false;
    }
  return true;
}

// Index of the first bit at or after `from` in a row of `bits` equal to `value`; `end` if none.
int next_bit(const uint64_t* row, int from, int end, bool value) {
  while (from < end) {
    const uint64_t word = value ? row[from / 64] : ~row[from / 64];
    const uint64_t masked = word & (~uint64_t(0) << (from % 64));
    if (masked) return std::min(end, (from / 64) * 64 + std::countr_zero(masked));
    from = (from / 64 + 1) * 64;
  }
  return end;
}

uint32_t find_root(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

}  // namespace

SurfaceVoxels::SurfaceVoxels(const Aabb& world, const SurfaceOccluderParams& params) : params_(params) {
  if (!(params.smallest_hole > 0.0) || !std::isfinite(params.smallest_hole))
    fail("--smallest-hole", std::to_string(params.smallest_hole) + " must be a finite number of metres > 0");
  if (!(params.smallest_occluder >= 0.0) || !std::isfinite(params.smallest_occluder))
    fail("--smallest-occluder", std::to_string(params.smallest_occluder) + " must be a finite number of metres >= 0");
  // A slit of width w holds a whole voxel across it when w >= 2 h √3 (docs/surface-occluders.md).
  h_ = params.smallest_hole / (2.0 * std::sqrt(3.0)) * 0.99;
  const Aabb box = world.empty() ? Aabb{Vec3(0.0f), Vec3(0.0f)} : world;
  uint64_t total = 1;
  for (int a = 0; a < 3; ++a) {
    origin_[a] = double(box.min[a]) - 2.0 * h_;
    const double count = std::ceil(double(box.size()[a]) / h_) + 4.0;
    if (!(count < 2.0e9)) total = params.max_voxels + 1;
    n_[a] = count < 2.0e9 ? int(count) : 1;
    total = total > params.max_voxels ? total : total * uint64_t(n_[a]);
  }
  if (total > params.max_voxels)
    fail("--smallest-hole " + std::to_string(params.smallest_hole),
         "the world's box needs more than " + std::to_string(params.max_voxels) +
             " voxels at this hole size; give a larger --smallest-hole");
  words_per_row_ = (size_t(n_[0]) + 63) / 64;
  surface_.assign(words_per_row_ * size_t(n_[1]) * size_t(n_[2]), 0);
  stats_.voxels = total;
  stats_.voxel_edge = h_;
}

int SurfaceVoxels::voxel_of(int axis, double x) const {
  const double at = std::floor((x - origin_[axis]) / h_);
  return int(std::clamp(at, 0.0, double(n_[axis] - 1)));
}

bool SurfaceVoxels::is_surface(int i, int j, int k) const {
  return (surface_[row(j, k) * words_per_row_ + size_t(i) / 64] >> (i % 64)) & 1u;
}

void SurfaceVoxels::add_mesh(const Mesh& mesh) {
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
    mark_triangle(glm::dvec3(mesh.positions[mesh.indices[t]]), glm::dvec3(mesh.positions[mesh.indices[t + 1]]),
                  glm::dvec3(mesh.positions[mesh.indices[t + 2]]));
}

void SurfaceVoxels::mark_triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const double margin = h_ * kMarginFraction;
  const glm::dvec3 half(0.5 * h_ + margin);
  int lo[3], hi[3];
  for (int axis = 0; axis < 3; ++axis) {
    lo[axis] = voxel_of(axis, std::min({a[axis], b[axis], c[axis]}) - margin);
    hi[axis] = voxel_of(axis, std::max({a[axis], b[axis], c[axis]}) + margin);
  }
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j) {
      uint64_t* words = surface_.data() + row(j, k) * words_per_row_;
      for (int i = lo[0]; i <= hi[0]; ++i) {
        const glm::dvec3 centre = origin_ + (glm::dvec3(i, j, k) + 0.5) * h_;
        const glm::dvec3 v[3] = {a - centre, b - centre, c - centre};
        if (!triangle_meets_box(v, half)) continue;
        std::atomic_ref<uint64_t>(words[i / 64]).fetch_or(uint64_t(1) << (i % 64), std::memory_order_relaxed);
      }
    }
}

void SurfaceVoxels::finish() {
  for (uint64_t word : surface_) stats_.surface_voxels += uint64_t(std::popcount(word));
  build_runs();
  join_components();
  derive_boxes();
}

void SurfaceVoxels::build_runs() {
  const size_t rows = size_t(n_[1]) * size_t(n_[2]);
  row_start_.assign(rows + 1, 0);
  for (size_t r = 0; r < rows; ++r) {
    row_start_[r] = runs_.size();
    const uint64_t* words = surface_.data() + r * words_per_row_;
    for (int i = next_bit(words, 0, n_[0], false); i < n_[0];) {
      const int end = next_bit(words, i, n_[0], true);
      runs_.push_back({uint32_t(i), uint32_t(end - 1)});
      i = next_bit(words, end, n_[0], false);
    }
  }
  row_start_[rows] = runs_.size();
  if (runs_.size() >= uint64_t(UINT32_MAX)) fail("--smallest-hole", "too many free runs; give a larger --smallest-hole");
  stats_.runs = runs_.size();
}

// Free voxels are 26-adjacent when their closed boxes share a point: in rows whose (j, k)
// differ by at most one, runs whose x ranges overlap once one is grown by a voxel. Each row
// is joined to the four neighbour rows that come before it in row order.
void SurfaceVoxels::join_components() {
  std::vector<uint32_t> parent(runs_.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto join_rows = [&](size_t ra, size_t rb) {
    uint64_t a = row_start_[ra], b = row_start_[rb];
    while (a < row_start_[ra + 1] && b < row_start_[rb + 1]) {
      if (runs_[a].x0 <= runs_[b].x1 + 1 && runs_[b].x0 <= runs_[a].x1 + 1) {
        const uint32_t x = find_root(parent, uint32_t(a)), y = find_root(parent, uint32_t(b));
        parent[std::max(x, y)] = std::min(x, y);
      }
      if (runs_[a].x1 + 1 < runs_[b].x1) ++a; else ++b;
    }
  };
  for (int k = 0; k < n_[2]; ++k)
    for (int j = 0; j < n_[1]; ++j) {
      const size_t r = row(j, k);
      if (j > 0) join_rows(r, row(j - 1, k));
      if (k > 0)
        for (int dj = -1; dj <= 1; ++dj)
          if (j + dj >= 0 && j + dj < n_[1]) join_rows(r, row(j + dj, k - 1));
    }
  component_.assign(runs_.size(), 0);
  std::vector<uint32_t> compact(runs_.size(), UINT32_MAX);
  uint32_t next = 0;
  for (size_t r = 0; r < runs_.size(); ++r) {
    const uint32_t root = find_root(parent, uint32_t(r));
    if (compact[root] == UINT32_MAX) compact[root] = next++;
    component_[r] = compact[root];
  }
  stats_.components = next;
}

const SurfaceVoxels::Run* SurfaceVoxels::run_over(int j, int k, int x0, int x1) const {
  const size_t r = row(j, k);
  const Run* first = runs_.data() + row_start_[r];
  const Run* last = runs_.data() + row_start_[r + 1];
  const Run* after = std::upper_bound(first, last, uint32_t(x0), [](uint32_t x, const Run& run) { return x < run.x0; });
  if (after == first) return nullptr;
  const Run* run = after - 1;
  return run->x1 >= uint32_t(x1) ? run : nullptr;
}

bool SurfaceVoxels::in_component(const Box& box, uint32_t component) const {
  for (int k = box.lo[2]; k <= box.hi[2]; ++k)
    for (int j = box.lo[1]; j <= box.hi[1]; ++j) {
      const Run* run = run_over(j, k, box.lo[0], box.hi[0]);
      if (!run || component_[size_t(run - runs_.data())] != component) return false;
    }
  return true;
}

// Grows the box one layer at a time, round robin over its six faces, while the new layer is
// free and in the component: a maximal box.
SurfaceVoxels::Box SurfaceVoxels::grown(Box box, uint32_t component) const {
  for (bool grew = true; grew;) {
    grew = false;
    for (int face = 0; face < 6; ++face) {
      const int axis = face / 2;
      const bool up = face % 2 == 1;
      if (up ? box.hi[axis] == n_[axis] - 1 : box.lo[axis] == 0) continue;
      Box layer = box;
      layer.lo[axis] = layer.hi[axis] = up ? box.hi[axis] + 1 : box.lo[axis] - 1;
      if (!in_component(layer, component)) continue;
      (up ? box.hi : box.lo)[axis] = layer.lo[axis];
      grew = true;
    }
  }
  return box;
}

// Greedy cover of every component by maximal boxes, seeded at the longest runs not yet
// covered; boxes thinner than the smallest occluder in their two longer edges are dropped
// (their voxels still count as covered, so they seed nothing more).
void SurfaceVoxels::derive_boxes() {
  std::vector<uint32_t> order(runs_.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return runs_[a].x1 - runs_[a].x0 > runs_[b].x1 - runs_[b].x0;
  });
  std::vector<uint64_t> covered(surface_.size(), 0);
  std::vector<size_t> run_row(runs_.size());
  for (size_t r = 0; r + 1 < row_start_.size(); ++r)
    for (uint64_t i = row_start_[r]; i < row_start_[r + 1]; ++i) run_row[i] = r;
  for (uint32_t index : order) {
    const Run& run = runs_[index];
    const size_t r = run_row[index];
    const uint64_t* words = covered.data() + r * words_per_row_;
    if (next_bit(words, int(run.x0), int(run.x1) + 1, false) > int(run.x1)) continue;  // all covered
    const int j = int(r % size_t(n_[1])), k = int(r / size_t(n_[1]));
    const Box box = grown({{int(run.x0), j, k}, {int(run.x1), j, k}}, component_[index]);
    for (int z = box.lo[2]; z <= box.hi[2]; ++z)
      for (int y = box.lo[1]; y <= box.hi[1]; ++y) {
        uint64_t* row_words = covered.data() + row(y, z) * words_per_row_;
        for (int x = box.lo[0]; x <= box.hi[0]; ++x) row_words[x / 64] |= uint64_t(1) << (x % 64);
      }
    double edges[3];
    for (int a = 0; a < 3; ++a) edges[a] = double(box.hi[a] - box.lo[a] + 1) * h_;
    std::sort(edges, edges + 3);
    if (edges[1] >= params_.smallest_occluder) occluders_.push_back({world_box(box), component_[index]});
  }
  stats_.boxes = occluders_.size();
}

Aabb SurfaceVoxels::world_box(const Box& box) const {
  Aabb out;
  for (int a = 0; a < 3; ++a) {
    // Free voxels keep kMarginFraction of an edge from every triangle; give half to rounding.
    const double margin = h_ * kMarginFraction * 0.5;
    out.min[a] = float(origin_[a] + box.lo[a] * h_ + margin);
    out.max[a] = float(origin_[a] + (box.hi[a] + 1) * h_ - margin);
  }
  return out;
}

uint32_t SurfaceVoxels::component_at(int i, int j, int k) const {
  const Run* run = run_over(j, k, i, i);
  return run ? component_[size_t(run - runs_.data())] : kSurface;
}

std::vector<uint32_t> SurfaceVoxels::components_near(const Aabb& region) const {
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0, voxel_of(a, region.min[a]) - 1);
    hi[a] = std::min(n_[a] - 1, voxel_of(a, region.max[a]) + 1);
  }
  std::vector<uint32_t> out;
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j) {
      const size_t r = row(j, k);
      for (uint64_t i = row_start_[r]; i < row_start_[r + 1]; ++i)
        if (int(runs_[i].x1) >= lo[0] && int(runs_[i].x0) <= hi[0]) out.push_back(component_[i]);
    }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace cellwalk::visibility
