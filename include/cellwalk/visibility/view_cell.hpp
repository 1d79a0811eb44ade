// View cells: a partition of the navigable space into boxes, each the region from which one
// precomputed visible set holds (HDoV thesis §5.2, vLOD §2.1/§6, stratified thesis ch. 3).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cellwalk/core/geometry.hpp"
#include "cellwalk/scene/scene.hpp"

namespace cellwalk {

using CellId = uint32_t;

struct ViewCell {
  CellId id = 0;
  Aabb box;
  uint32_t depth = 0;   // 0 for grid cells; the subdivision depth in octrees and k-d trees
  bool solid = false;   // inside an object: no viewer can stand here, no set is computed
  // Left out of the run (`pvs --along`): a viewer may stand here, but no set was computed, so
  // none may be assumed (neither empty nor a neighbour's).
  bool skipped = false;
  // Whether the cell has a set: neither solid nor skipped.
  bool computed() const { return !solid && !skipped; }
};

// Thread-safety: const methods may be called concurrently.
class ViewCellPartition {
 public:
  virtual ~ViewCellPartition() = default;
  virtual std::string kind() const = 0;  // "grid", "octree", "kd"
  virtual size_t cell_count() const = 0;
  // Cell ids are dense, 0 .. cell_count() - 1, and stable: they are stored in the world file.
  virtual const ViewCell& cell(CellId id) const = 0;
  // The leaf cell containing p (boundary points go to the cell with the larger coordinate),
  // nullopt outside the partition.
  virtual std::optional<CellId> locate(const Vec3& p) const = 0;
  // Cells sharing a face with `id`, including across octree / k-d levels.
  virtual std::vector<CellId> face_neighbours(CellId id) const = 0;
};

// ---- Building partitions ------------------------------------------------------------------
// All three kinds are trees of boxes over a grid of roots (a grid: roots only; an octree: a
// grid of roots, each subdivided; a k-d tree: one root split in two), so one implementation
// answers locate() and face_neighbours() for all, and one serialisation stores them.

// The region view cells cover. In 2D (the city seeds' walkers stay at eye height) cells span
// the whole eye-height range [eye_min, eye_max] in y and are split only in x and z.
struct CellRegion {
  Aabb bounds;              // x and z extent (and y in 3D)
  bool two_d = true;
  float eye_min = 1.45f;    // y range of 2D cells
  float eye_max = 1.95f;
};

// The default region of a world: its bounds and the navigation graph's nodes (padded by 1 m)
// in x/z, and in 2D the nodes' heights padded by 0.25 m (1.7 m ± 0.25 m when the graph is empty).
CellRegion default_cell_region(const Aabb& bounds, const NavGraph& nav, bool two_d);

// Whether a cell box is inside solid matter (see EmbreeScene::box_is_solid). Cells it accepts
// are marked solid, get no visible set and are never subdivided. Empty: nothing is solid.
using SolidTest = std::function<bool(const Aabb&)>;

// The most cells of a grid (and of the root grid of a kd-tree or octree): more would take days to
// compute and gigabytes to hold, so a finer cell size is refused before any cell is made.
constexpr uint64_t kMaxGridCells = 1'000'000;

// A uniform grid of cubes of side `cell_size` (the last row/column may be shorter) covering the
// region. A cell size that is not finite and positive, or one making more than kMaxGridCells
// cells, fails with an Error.
std::unique_ptr<ViewCellPartition> make_grid_partition(const CellRegion& region, float cell_size,
                                                       const SolidTest& solid = {});

// The size of a candidate cell's visible set (vLOD uses triangles; any monotone measure works).
// Called concurrently for different boxes.
using CellSetSize = std::function<uint64_t(const Aabb&)>;

// vLOD §2.1 (digest 001 §3.1): a grid of `root_size` cubes, each the root of an octree (a
// quadtree in x/z in 2D). A cell is subdivided while set_size(cell) > threshold, unless the
// futility rule holds (set_size(cell) <= 2 * min over its children) or the cell is at
// max_depth.
struct OctreeRules {
  float root_size = 64.0f;
  uint64_t threshold = 200;
  uint32_t max_depth = 3;
};
std::unique_ptr<ViewCellPartition> make_octree_partition(const CellRegion& region,
                                                         const OctreeRules& rules,
                                                         const CellSetSize& set_size,
                                                         const SolidTest& solid = {});

// Stratified thesis §3.1.1 (digest 002 §3.5): one root over the region, split in half along its
// longest splittable axis (y never in 2D) at the multiple of `viewcell_size` nearest the
// middle, while the cell is longer than viewcell_size along some axis. Leaves are the cells.
std::unique_ptr<ViewCellPartition> make_kd_partition(const CellRegion& region, float viewcell_size,
                                                     const SolidTest& solid = {});
// One split of that tree: the two halves of `box` (lower first), or nullopt when `box` is a
// leaf. `origin` is the region's minimum corner. Lets a builder walk the tree make_kd_partition
// makes (the stratified near lists, built depth first) without holding it.
std::optional<std::array<Aabb, 2>> kd_split(const Aabb& box, const Vec3& origin, float viewcell_size, bool two_d);

// A copy of `partition` in which every non-solid cell that `keep` rejects is marked skipped
// (ids, boxes and neighbours unchanged). Throws Error for a partition cellwalk did not make.
std::unique_ptr<ViewCellPartition> skip_cells(const ViewCellPartition& partition,
                                              const std::function<bool(const ViewCell&)>& keep);

// Throws the Error a run-time system gives when its camera at `p` stands in a skipped cell:
// it has no set to use, and it says how to compute one.
[[noreturn]] void fail_in_skipped_cell(const std::string& system, const ViewCell& cell, const Vec3& p);

// The "cells" section of a world file (layout in docs/format.md, "Visibility sections"), and
// back. Reading checks every field and throws Error naming `where` on damage.
std::vector<uint8_t> serialize_partition(const ViewCellPartition& partition);
std::unique_ptr<ViewCellPartition> deserialize_partition(std::span<const uint8_t> bytes,
                                                         const std::string& where);

}  // namespace cellwalk
