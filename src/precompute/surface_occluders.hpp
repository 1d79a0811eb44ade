// Occluders from the world's surfaces, however it is split into objects: a world-wide
// conservative voxelisation whose free voxels fall into components, and boxes inside each
// component that hide, from any region lying in none of the components it may touch,
// whatever lies behind them (docs/surface-occluders.md: the argument and its limits).
// Seeds: 001 vLOD §5.2.2 (occluders must be solid and convex; concave volume needs a
// conservative stand-in: here boxes in enclosed free space) and §5.3 (occluders larger than
// the cell matter most; the smallest occluder drops the rest).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "cellwalk/core/geometry.hpp"
#include "cellwalk/scene/mesh.hpp"

namespace cellwalk::visibility {

struct SurfaceOccluderParams {
  // Openings at least this wide (metres) stay open; narrower ones may be closed (the voxel
  // edge is smallest_hole / (2√3), less a margin). REQUIRES > 0.
  double smallest_hole = 0.25;
  // Boxes whose second-longest edge is shorter than this (metres) are dropped.
  double smallest_occluder = 1.0;
  // The grid is refused (Error naming the size it needs) above this many voxels.
  uint64_t max_voxels = uint64_t(1) << 30;
};

struct SurfaceOccluder {
  Aabb box;
  uint32_t component;
};

struct SurfaceVoxelStats {
  uint64_t voxels = 0, surface_voxels = 0, runs = 0, components = 0, boxes = 0;
  double voxel_edge = 0.0;
};

// Thread-safety: add_mesh may be called from several threads at once; the rest after
// finish(), from any number of threads (const).
class SurfaceVoxels {
 public:
  // A grid over `world` (the box of all geometry) grown by two voxels on every side, so its
  // border voxels are free and join one component around everything. Throws Error when it
  // would need more than params.max_voxels.
  SurfaceVoxels(const Aabb& world, const SurfaceOccluderParams& params);

  // Marks every voxel whose closed box meets a triangle of `mesh` (triangle–box separating
  // axes in double precision, the box grown by a rounding margin: doubt marks it surface).
  void add_mesh(const Mesh& mesh);

  // Joins the free voxels into 26-connected components and derives the occluder boxes.
  // REQUIRES: every mesh added.
  void finish();

  // The components a viewpoint in `region` may lie in: those of the free voxels meeting the
  // region grown by one voxel (the free voxels meeting it, and those next to the surface
  // voxels meeting it). Sorted, unique.
  std::vector<uint32_t> components_near(const Aabb& region) const;

  // The grid, for tests and reports: voxels per axis, and voxel (i, j, k)'s component
  // (kSurface where a triangle meets it). REQUIRES finish() for component_at.
  static constexpr uint32_t kSurface = UINT32_MAX;
  std::array<int, 3> dims() const { return {n_[0], n_[1], n_[2]}; }
  glm::dvec3 origin() const { return origin_; }
  uint32_t component_at(int i, int j, int k) const;

  const std::vector<SurfaceOccluder>& occluders() const { return occluders_; }
  const SurfaceVoxelStats& stats() const { return stats_; }
  double voxel_edge() const { return h_; }

 private:
  struct Run {
    uint32_t x0, x1;  // inclusive voxel range along x of free voxels in one row
  };
  struct Box {
    int lo[3], hi[3];  // inclusive voxel ranges
  };

  SurfaceOccluderParams params_;
  double h_;
  glm::dvec3 origin_;
  int n_[3];
  size_t words_per_row_;
  std::vector<uint64_t> surface_;     // one bit per voxel, rows of words_per_row_ words
  std::vector<uint64_t> row_start_;   // runs of row r: runs_[row_start_[r] .. row_start_[r+1])
  std::vector<Run> runs_;
  std::vector<uint32_t> component_;   // per run
  std::vector<SurfaceOccluder> occluders_;
  SurfaceVoxelStats stats_;

  size_t row(int j, int k) const { return size_t(k) * size_t(n_[1]) + size_t(j); }
  bool is_surface(int i, int j, int k) const;
  int voxel_of(int axis, double x) const;
  void mark_triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);
  void build_runs();
  void join_components();
  // The run of row (j, k) holding all of [x0, x1], or nullptr.
  const Run* run_over(int j, int k, int x0, int x1) const;
  bool in_component(const Box& box, uint32_t component) const;
  Box grown(Box box, uint32_t component) const;
  void derive_boxes();
  Aabb world_box(const Box& box) const;
};

}  // namespace cellwalk::visibility
