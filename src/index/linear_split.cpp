// Ang & Tan's linear node split (SSD 1997); HDoV thesis §2.2.1 and §4.1, digest §3.2.
#include "index/linear_split.hpp"

#include <algorithm>
#include <array>

namespace cellwalk {
namespace {

double volume(const Aabb& box) {
  if (box.empty()) return 0.0;
  const Vec3 s = box.size();
  return double(s.x) * double(s.y) * double(s.z);
}

Aabb bounds_of(const std::vector<RTreeEntry>& entries, const std::vector<size_t>& which) {
  Aabb box;
  for (size_t i : which) box.extend(entries[i].box);
  return box;
}

double overlap_volume(const Aabb& a, const Aabb& b) {
  if (a.empty() || b.empty() || !a.overlaps(b)) return 0.0;
  Aabb both;
  both.min = glm::max(a.min, b.min);
  both.max = glm::min(a.max, b.max);
  return volume(both);
}

struct AxisSplit {
  std::vector<size_t> low, high;  // indices of entries nearer the low / high border
  size_t larger = 0;              // max(|low|, |high|): smaller is more even
  double overlap = 0.0, coverage = 0.0;
};

AxisSplit split_on_axis(const std::vector<RTreeEntry>& entries, const Aabb& node, int axis) {
  AxisSplit s;
  for (size_t i = 0; i < entries.size(); ++i) {
    const double to_low = double(entries[i].box.min[axis]) - node.min[axis];
    const double to_high = double(node.max[axis]) - entries[i].box.max[axis];
    // Equidistant entries (e.g. boxes spanning the node) balance the lists.
    const bool low = to_low < to_high || (to_low == to_high && s.low.size() <= s.high.size());
    (low ? s.low : s.high).push_back(i);
  }
  s.larger = std::max(s.low.size(), s.high.size());
  const Aabb a = bounds_of(entries, s.low), b = bounds_of(entries, s.high);
  s.overlap = overlap_volume(a, b);
  s.coverage = volume(a) + volume(b);
  return s;
}

bool better(const AxisSplit& a, const AxisSplit& b) {
  if (a.larger != b.larger) return a.larger < b.larger;
  if (a.overlap != b.overlap) return a.overlap < b.overlap;
  return a.coverage < b.coverage;
}

// Moves entries from `from` to `to` until `to` holds `min_entries`: those whose far side lies
// nearest `to`'s border go first.
void refill(const std::vector<RTreeEntry>& entries, int axis, bool to_is_low, std::vector<size_t>& from,
            std::vector<size_t>& to, uint32_t min_entries) {
  if (to.size() >= min_entries) return;
  std::sort(from.begin(), from.end(), [&](size_t x, size_t y) {
    return to_is_low ? entries[x].box.min[axis] < entries[y].box.min[axis]
                     : entries[x].box.max[axis] > entries[y].box.max[axis];
  });
  const size_t move = min_entries - to.size();
  to.insert(to.end(), from.begin(), from.begin() + static_cast<std::ptrdiff_t>(move));
  from.erase(from.begin(), from.begin() + static_cast<std::ptrdiff_t>(move));
}

}  // namespace

std::pair<std::vector<RTreeEntry>, std::vector<RTreeEntry>> linear_split(std::vector<RTreeEntry> entries,
                                                                         uint32_t min_entries) {
  Aabb node;
  for (const RTreeEntry& e : entries) node.extend(e.box);
  int best_axis = 0;
  AxisSplit best = split_on_axis(entries, node, 0);
  for (int axis = 1; axis < 3; ++axis) {
    AxisSplit s = split_on_axis(entries, node, axis);
    if (better(s, best)) {
      best = std::move(s);
      best_axis = axis;
    }
  }
  refill(entries, best_axis, true, best.high, best.low, min_entries);
  refill(entries, best_axis, false, best.low, best.high, min_entries);
  std::pair<std::vector<RTreeEntry>, std::vector<RTreeEntry>> out;
  for (size_t i : best.low) out.first.push_back(entries[i]);
  for (size_t i : best.high) out.second.push_back(entries[i]);
  return out;
}

}  // namespace cellwalk
