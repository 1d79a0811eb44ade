// The worlds of `cellwalk bench visual` (HDoV thesis §5.8.1, digest §5.1): a generated city,
// per-cell DoVs from the `dov` engine over a set of view cells, and the HDoV-tree built from
// them. One city can carry several cell sets (the grid of Exps. 1–2, the walk's cells of Exp. 3),
// each written as its own world file.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "cellwalk/systems/visual/hdov_tree.hpp"
#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/visibility/view_cell.hpp"
#include "cellwalk/store/world.hpp"
#include "experiments/visual/visual_report.hpp"

namespace cellwalk::visual_bench {

// Generates a city of `objects` buildings and builds its world (LOD chains and the R-tree REVIEW
// queries) at dir/<name>.cww, without visibility sections. Returns the world file.
std::string build_city(const VisualBenchParams& p, uint64_t objects, const std::filesystem::path& dir,
                       const std::string& name);

// A city world with DoVs over one cell set and its HDoV-tree.
struct TreeWorld {
  std::string world_file, tree_file;
  std::unique_ptr<World> world;
  std::unique_ptr<HdovTree> tree;
  uint64_t visible_nodes = 0;  // Σ over cells of N_vnode
  size_t dov_cells = 0;        // cells whose DoV was computed (the others are solid or skipped)
  double dov_seconds = 0, tree_seconds = 0;
};

// Computes the DoV of every cell of `cells` that is neither solid nor skipped over the city `raw` (at p.dov_resolution),
// writes dir/<name>.cww with them and builds dir/<name>.cww.hdov (fan-out p.fanout).
TreeWorld add_dov_and_tree(const VisualBenchParams& p, const std::string& raw, const ViewCellPartition& cells,
                           const std::filesystem::path& dir, const std::string& name);

// The side of a grid of `per_side` cells over the city (the default grid of Exps. 1–2).
float grid_cell_side(const World& city, int per_side);
// A grid of cells of `side` over the whole city.
std::unique_ptr<ViewCellPartition> city_grid(const World& city, float side);
// A block of at most per_side × per_side cells of `side` around the city's centre (Fig. 5.23:
// the same cell size and count in every city, so only the world grows).
std::unique_ptr<ViewCellPartition> central_grid(const World& city, float side, int per_side);
// A grid of cells of `side` over the path's x/z box in which only the cells the path enters get a
// DoV (the rest are skipped, as `pvs --along` skips them): Exp. 3's cell changes without
// precomputing empty streets.
std::unique_ptr<ViewCellPartition> path_grid(const World& city, const CameraPath& path, float side);

}  // namespace cellwalk::visual_bench
