// Ground-truth visible sets: union of ID cube maps from the cell's corners and random points
// inside and on its faces (issue 4's check; the cube maps of HDoV thesis §5.5.2 at high
// resolution).
#include "precompute/ground_truth.hpp"

#include <algorithm>
#include <chrono>
#include <iterator>

#include "precompute/cell_points.hpp"

namespace cellwalk::visibility {

std::vector<ObjectId> ground_truth_visible(const CubeMapSource& cube, const ViewCell& cell,
                                           const GroundTruthOptions& options) {
  Random rng(options.seed ^ (uint64_t(cell.id) * 0x9E3779B97F4A7C15ull));
  std::vector<Vec3> points = cell_corners(cell.box);
  for (const Vec3& p : cell_random_points(cell.box, options.points, rng)) points.push_back(p);
  std::vector<bool> seen;
  for (const Vec3& p : points)
    for (const IdImage& face : cube.render(p))
      for (uint32_t id : face.ids) {
        if (id == kBackgroundId) continue;
        if (id > seen.size()) seen.resize(id, false);
        seen[id - 1] = true;
      }
  std::vector<ObjectId> out;
  for (size_t i = 0; i < seen.size(); ++i)
    if (seen[i]) out.push_back(ObjectId(i));
  return out;
}

}  // namespace cellwalk::visibility

namespace cellwalk::visibility {

std::vector<CellId> cells_to_check(const ViewCellPartition& partition, uint64_t count) {
  std::vector<CellId> open;
  for (CellId c = 0; c < partition.cell_count(); ++c)
    if (partition.cell(c).computed()) open.push_back(c);
  if (open.size() <= count) return open;
  std::vector<CellId> out;
  for (uint64_t i = 0; i < count; ++i) out.push_back(open[(2 * i + 1) * open.size() / (2 * count)]);
  return out;
}

CellCheck check_cell(const VisibilityEngine& engine, const CubeMapSource& cube, const ViewCell& cell,
                     const GroundTruthOptions& options) {
  CellCheck check;
  check.cell = cell.id;
  auto t0 = std::chrono::steady_clock::now();
  const VisibleSet set = engine.compute(cell);
  auto t1 = std::chrono::steady_clock::now();
  const std::vector<ObjectId> truth = ground_truth_visible(cube, cell, options);
  auto t2 = std::chrono::steady_clock::now();
  check.engine_seconds = std::chrono::duration<double>(t1 - t0).count();
  check.truth_seconds = std::chrono::duration<double>(t2 - t1).count();
  check.set_size = set.objects.size();
  check.truth_size = truth.size();
  std::set_difference(truth.begin(), truth.end(), set.objects.begin(), set.objects.end(),
                      std::back_inserter(check.missed));
  check.found = truth.size() - check.missed.size();
  return check;
}

}  // namespace cellwalk::visibility
