// Seed 004 (Zheng), §7.2: SNP and PBNP prefetching areas on a grid of view cells.
#include "cellwalk/systems/pvs_stream/pvs_prefetch.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "cellwalk/core/error.hpp"

namespace cellwalk::pvs_stream {

int chebyshev(GridCell a, GridCell b) { return std::max(std::abs(a.row - b.row), std::abs(a.col - b.col)); }

const char* region_name(Region region) {
  static const char* const kNames[] = {"M", "N", "S", "E", "W", "NW", "NE", "SE", "SW"};
  return kNames[size_t(region)];
}

const char* algorithm_name(PrefetchAlgorithm algorithm) { return algorithm == PrefetchAlgorithm::snp ? "SNP" : "PBNP"; }

ViewcellGrid::ViewcellGrid(int rows, int cols, double cell_size, std::vector<uint8_t> present)
    : rows_(rows), cols_(cols), cell_size_(cell_size), present_(std::move(present)) {
  if (rows <= 0 || cols <= 0 || !(cell_size > 0) || present_.size() != size_t(rows) * size_t(cols))
    throw Error("view cell grid: " + std::to_string(rows) + " × " + std::to_string(cols) + " cells of " +
                std::to_string(cell_size) + " m with " + std::to_string(present_.size()) + " flags is not a grid");
  view_cells_ = uint32_t(std::count_if(present_.begin(), present_.end(), [](uint8_t p) { return p != 0; }));
}

bool ViewcellGrid::contains(GridCell cell) const {
  return cell.row >= 0 && cell.row < rows_ && cell.col >= 0 && cell.col < cols_ && present_[index(cell)] != 0;
}

GridCell ViewcellGrid::cell_at(double x, double z) const {
  return {int(std::floor(z / cell_size_)), int(std::floor(x / cell_size_))};
}

Region ViewcellGrid::region_at(double x, double z, double band) const {
  const double u = x / cell_size_ - std::floor(x / cell_size_);  // 0 at the west edge
  const double v = z / cell_size_ - std::floor(z / cell_size_);  // 0 at the north edge
  const int ew = u < band ? -1 : (u >= 1.0 - band ? 1 : 0);
  const int ns = v < band ? -1 : (v >= 1.0 - band ? 1 : 0);
  static const Region kTable[3][3] = {{Region::NW, Region::N, Region::NE},
                                      {Region::W, Region::M, Region::E},
                                      {Region::SW, Region::S, Region::SE}};
  return kTable[ns + 1][ew + 1];
}

std::vector<std::pair<int, int>> h_offsets(Region region) {
  // (row, column) offsets: north is row − 1, east is column + 1.
  switch (region) {
    case Region::M: return {{0, 0}};
    case Region::N: return {{0, 0}, {-1, 0}};
    case Region::S: return {{0, 0}, {1, 0}};
    case Region::E: return {{0, 0}, {0, 1}};
    case Region::W: return {{0, 0}, {0, -1}};
    case Region::NW: return {{0, 0}, {-1, 0}, {0, -1}, {-1, -1}};
    case Region::NE: return {{0, 0}, {-1, 0}, {0, 1}, {-1, 1}};
    case Region::SE: return {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    case Region::SW: return {{0, 0}, {1, 0}, {0, -1}, {1, -1}};
  }
  return {{0, 0}};
}

std::vector<GridCell> prefetching_area(PrefetchAlgorithm algorithm, const ViewcellGrid& grid, GridCell cell,
                                       Region region) {
  std::vector<std::pair<int, int>> offsets;
  if (algorithm == PrefetchAlgorithm::pbnp) {
    offsets = h_offsets(region);
  } else {
    offsets.push_back({0, 0});
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc)
        if (dr != 0 || dc != 0) offsets.push_back({dr, dc});
  }
  std::vector<GridCell> area;
  for (const auto& [dr, dc] : offsets) {
    const GridCell c{cell.row + dr, cell.col + dc};
    if (grid.contains(c)) area.push_back(c);
  }
  return area;
}

}  // namespace cellwalk::pvs_stream
