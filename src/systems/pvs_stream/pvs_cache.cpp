// Seed 004 (Zheng), §7.3 delta transmission and §7.4 client-side cache management.
#include "cellwalk/systems/pvs_stream/pvs_cache.hpp"

#include <algorithm>
#include <iterator>

#include "cellwalk/core/error.hpp"

namespace cellwalk::pvs_stream {

std::vector<uint32_t> union_of(const std::vector<const std::vector<uint32_t>*>& rows) {
  std::vector<uint32_t> out;
  for (const std::vector<uint32_t>* row : rows) {
    std::vector<uint32_t> merged;
    merged.reserve(out.size() + row->size());
    std::set_union(out.begin(), out.end(), row->begin(), row->end(), std::back_inserter(merged));
    out.swap(merged);
  }
  return out;
}

std::vector<uint32_t> minus(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  std::vector<uint32_t> out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

size_t replacement_victim(const std::vector<GridCell>& cells, const std::vector<GridCell>& area, GridCell current) {
  const auto in_area = [&](const GridCell& c) { return std::find(area.begin(), area.end(), c) != area.end(); };
  size_t victim = cells.size();
  int victim_distance = 0;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (in_area(cells[i])) continue;
    const int d = chebyshev(cells[i], current);
    if (d > victim_distance) {  // the farthest; among equals the oldest (first found)
      victim = i;
      victim_distance = d;
    }
  }
  if (victim < cells.size() && victim_distance > 1) return victim;
  // Every row left neighbours the viewpoint: only a table smaller than 9 gets here; replace the
  // oldest row outside the area.
  for (size_t i = 0; i < cells.size(); ++i)
    if (!in_area(cells[i])) return i;
  return cells.size();
}

ClientPvsCache::ClientPvsCache(const ViewcellGrid& grid, const PvsTable& table, size_t entries)
    : grid_(grid), table_(table), entries_(entries) {
  if (entries == 0) throw Error("PVS cache: it needs at least one entry");
  if (table.rows.size() != grid.cell_count())
    throw Error("PVS cache: the table has " + std::to_string(table.rows.size()) + " rows for a grid of " +
                std::to_string(grid.cell_count()) + " cells");
}

bool ClientPvsCache::cached(GridCell cell) const { return std::find(cells_.begin(), cells_.end(), cell) != cells_.end(); }

Transaction ClientPvsCache::update(GridCell current, const std::vector<GridCell>& area) {
  Transaction t;
  for (const GridCell& c : area)
    if (!cached(c)) t.requested.push_back(c);
  if (t.requested.empty()) return t;
  // §7.3: S_J − S_I. The database holds exactly S_I (the invariant this class keeps).
  std::vector<const std::vector<uint32_t>*> requested_rows;
  for (const GridCell& c : t.requested) requested_rows.push_back(&table_.rows[grid_.index(c)]);
  t.delta = minus(union_of(requested_rows), objects_);
  std::vector<uint32_t> merged;
  std::set_union(objects_.begin(), objects_.end(), t.delta.begin(), t.delta.end(), std::back_inserter(merged));
  objects_.swap(merged);
  cells_.insert(cells_.end(), t.requested.begin(), t.requested.end());

  // §7.4: replace rows while over capacity; never one of the area (REQUIRES: it fits).
  while (cells_.size() > entries_) {
    const size_t victim = replacement_victim(cells_, area, current);
    if (victim == cells_.size()) throw Error("PVS cache: the prefetching area has more cells than the cache entries");
    t.evicted.push_back(cells_[victim]);
    cells_.erase(cells_.begin() + ptrdiff_t(victim));
  }
  if (!t.evicted.empty()) {
    std::vector<const std::vector<uint32_t>*> evicted_rows, kept_rows;
    for (const GridCell& c : t.evicted) evicted_rows.push_back(&table_.rows[grid_.index(c)]);
    for (const GridCell& c : cells_) kept_rows.push_back(&table_.rows[grid_.index(c)]);
    const std::vector<uint32_t> kept = union_of(kept_rows);
    t.dropped = minus(union_of(evicted_rows), kept);
    objects_ = minus(objects_, t.dropped);
  }
  return t;
}

}  // namespace cellwalk::pvs_stream
