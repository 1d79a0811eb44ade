// The client-side cache of Zheng's PVS streaming (seed 004, §7.3 delta transmission, §7.4 cache
// management; digest §3.11): at most `entries` rows of the PVS table (the local PVS table) and
// the objects of their union (the local graphical database), kept consistent with them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "cellwalk/systems/pvs_stream/pvs_prefetch.hpp"

namespace cellwalk::pvs_stream {

// The PVS table T: one row S_i per cell of the grid (index order), each the sorted ids of the
// objects visible from it; empty for a missing cell.
struct PvsTable {
  std::vector<std::vector<uint32_t>> rows;
  uint32_t objects = 0;  // the scene's object count (ids are below it)
};

// Sorted-set helpers: the union of sorted rows, and a − b.
std::vector<uint32_t> union_of(const std::vector<const std::vector<uint32_t>*>& rows);
std::vector<uint32_t> minus(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b);

// §7.4's choice of the row to replace among `cells` (oldest first) with the viewpoint in `current`:
// never a cell of `area`; a row that is no neighbour of `current` (D_r > 1 or D_c > 1), the
// farthest first, then the oldest; failing that the oldest outside the area. cells.size() when
// every row is in the area.
size_t replacement_victim(const std::vector<GridCell>& cells, const std::vector<GridCell>& area, GridCell current);

// What one prefetching transaction did.
struct Transaction {
  std::vector<GridCell> requested;  // J: the rows fetched (the area's cells not cached)
  std::vector<uint32_t> delta;      // ΔS = S_J − S_I: the objects sent (§7.3)
  std::vector<GridCell> evicted;    // d: the rows replaced (§7.4)
  std::vector<uint32_t> dropped;    // ΔS_d = S_d − S_c: the objects deleted with them
};

// Thread-safety: none; one client's cache.
class ClientPvsCache {
 public:
  // REQUIRES: entries >= 1.
  explicit ClientPvsCache(const ViewcellGrid& grid, const PvsTable& table, size_t entries = 9);

  // Makes every cell of `area` cached, the viewpoint being in `current`. The rows not cached are
  // requested in one transaction and only the objects the cache lacks are sent (ΔS = S_J − S_I,
  // S_I the union of the cached rows). While the table then holds more than `entries` rows, a row
  // that is no neighbour of `current` (D_r > 1 or D_c > 1) is replaced, the farthest first, then
  // the oldest; the objects no kept row sees are deleted (ΔS_d = S_d − S_c). An empty
  // transaction when the whole area was cached.
  // REQUIRES: area.size() <= entries; every cell of `area` is a view cell within 1 of `current`.
  Transaction update(GridCell current, const std::vector<GridCell>& area);

  const std::vector<GridCell>& cached_cells() const { return cells_; }  // oldest first
  bool cached(GridCell cell) const;
  // The local graphical database: the sorted ids of the objects held.
  const std::vector<uint32_t>& objects() const { return objects_; }

 private:
  const ViewcellGrid& grid_;
  const PvsTable& table_;
  size_t entries_;
  std::vector<GridCell> cells_;
  std::vector<uint32_t> objects_;
};

}  // namespace cellwalk::pvs_stream
