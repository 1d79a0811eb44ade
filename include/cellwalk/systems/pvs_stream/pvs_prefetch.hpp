// Zheng's PVS prefetch on a uniform grid of view cells (seed 004, Zheng, ch. 7, §7.2; digest
// §3.10): SNP (Koltun et al.: the current cell and its 8 neighbours, checked when the viewpoint
// crosses a cell border) and PBNP (each cell split into 9 regions, checked when it crosses a
// region border; the cells that must be cached are h(R) of Table 7.1).
#pragma once

#include <compare>
#include <cstdint>
#include <utility>
#include <vector>

namespace cellwalk::pvs_stream {

// A cell of the grid. Rows grow southward (+z), columns eastward (+x): the north neighbour of
// (r, c) is (r − 1, c), as in the thesis's Figure 7.1.
struct GridCell {
  int row = 0, col = 0;
  auto operator<=>(const GridCell&) const = default;
};

// The larger of the row and column distances: 1 for the 8 neighbours (§7.4's D_r, D_c).
int chebyshev(GridCell a, GridCell b);

// The nine regions of a cell (Figure 7.2).
enum class Region : uint8_t { M, N, S, E, W, NW, NE, SE, SW };
const char* region_name(Region region);

// A uniform grid of square view cells over the x-z plane from (0, 0). A cell may be missing (the
// inside of a building holds no view cell): it is never required and never prefetched (the
// thesis is silent; digest §7.4).
class ViewcellGrid {
 public:
  // REQUIRES: rows, cols > 0; cell_size > 0; present.size() == rows * cols (1: a view cell).
  ViewcellGrid(int rows, int cols, double cell_size, std::vector<uint8_t> present);

  int rows() const { return rows_; }
  int cols() const { return cols_; }
  double cell_size() const { return cell_size_; }
  // In the grid and a view cell.
  bool contains(GridCell cell) const;
  // REQUIRES: contains(cell).
  uint32_t index(GridCell cell) const { return uint32_t(cell.row) * uint32_t(cols_) + uint32_t(cell.col); }
  GridCell cell_of(uint32_t index) const { return {int(index / uint32_t(cols_)), int(index % uint32_t(cols_))}; }
  uint32_t cell_count() const { return uint32_t(rows_) * uint32_t(cols_); }
  uint32_t view_cell_count() const { return view_cells_; }
  // The cell holding (x, z) (cells own their low edges), whether or not it is a view cell.
  GridCell cell_at(double x, double z) const;
  // The region of (x, z) in its cell: bands `band` × cell size wide along each side, the corners
  // where two bands meet, the middle the rest. REQUIRES: 0 < band < 0.5.
  Region region_at(double x, double z, double band) const;

 private:
  int rows_, cols_;
  double cell_size_;
  std::vector<uint8_t> present_;
  uint32_t view_cells_ = 0;
};

enum class PrefetchAlgorithm { snp, pbnp };
const char* algorithm_name(PrefetchAlgorithm algorithm);

// Table 7.1: the (row, column) offsets of h(R) from the current cell, the cell itself first.
std::vector<std::pair<int, int>> h_offsets(Region region);

// The view cells that must be cached with the viewpoint in `region` of `cell` (the prefetching
// area), `cell` first: SNP the 3 × 3 block around it, PBNP h(R); missing cells are left out.
std::vector<GridCell> prefetching_area(PrefetchAlgorithm algorithm, const ViewcellGrid& grid, GridCell cell,
                                       Region region);

}  // namespace cellwalk::pvs_stream
