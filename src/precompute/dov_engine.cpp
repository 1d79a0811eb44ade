// Degree of visibility by cubic projection, HDoV thesis §5.5.2–§5.5.3 (digest 000 §3.9):
// point DoV = Σ eq. 5.11 weights of the pixels showing the object in the ID cube map at a
// point; region DoV = max over the cell's 8 corners (eq. 5.2 sampled at the vertices, as the
// thesis does); internal nodes sum their members per corner (group_dov).
#include "precompute/dov_engine.hpp"

#include <algorithm>
#include <unordered_map>

#include "precompute/cell_points.hpp"

namespace cellwalk::visibility {

DovEngine::DovEngine(const World& world, const EngineOptions& options, const VisibilityEngine* prior)
    : prior_(prior),
      cube_(world, options.dov_resolution),
      weights_(cube_pixel_weights(options.dov_resolution, options.dov_midpoint_weights)),
      smallest_(*std::min_element(weights_.begin(), weights_.end())) {}

CornerDov DovEngine::compute_corners(const ViewCell& cell) const {
  const std::vector<Vec3> corners = cell_corners(cell.box);
  std::vector<std::unordered_map<ObjectId, double>> point_dov(corners.size());
  for (size_t c = 0; c < corners.size(); ++c) {
    const CubeIds faces = cube_.render(corners[c]);
    for (const IdImage& face : faces)
      for (size_t px = 0; px < face.ids.size(); ++px)
        if (face.ids[px] != kBackgroundId) point_dov[c][face.ids[px] - 1] += weights_[px];
  }
  CornerDov out;
  for (const auto& m : point_dov)
    for (const auto& [id, dov] : m) out.objects.push_back(id);
  std::sort(out.objects.begin(), out.objects.end());
  out.objects.erase(std::unique(out.objects.begin(), out.objects.end()), out.objects.end());
  for (const auto& m : point_dov) {
    std::vector<float> row(out.objects.size(), 0.0f);
    for (size_t i = 0; i < out.objects.size(); ++i)
      if (auto it = m.find(out.objects[i]); it != m.end()) row[i] = float(it->second);
    out.dov.push_back(std::move(row));
  }
  return out;
}

VisibleSet DovEngine::compute(const ViewCell& cell) const {
  const CornerDov corners = compute_corners(cell);
  std::unordered_map<ObjectId, float> region;
  for (size_t i = 0; i < corners.objects.size(); ++i)
    for (const auto& row : corners.dov) region[corners.objects[i]] = std::max(region[corners.objects[i]], row[i]);
  // Thesis step 1 found these visible, yet no corner's pixel shows them: DoV_s, not zero.
  if (prior_)
    for (ObjectId id : prior_->compute(cell).objects) region.try_emplace(id, float(smallest_));
  VisibleSet set;
  for (const auto& [id, dov] : region) set.objects.push_back(id);
  std::sort(set.objects.begin(), set.objects.end());
  for (ObjectId id : set.objects) set.dov.push_back(region[id]);
  return set;
}

}  // namespace cellwalk::visibility

namespace cellwalk {

float group_dov(const CornerDov& corners, std::span<const ObjectId> members) {
  double best = 0.0;
  for (const auto& row : corners.dov) {
    double sum = 0.0;
    size_t i = 0;
    // Both lists ascend: one merge pass.
    for (ObjectId m : members) {
      while (i < corners.objects.size() && corners.objects[i] < m) ++i;
      if (i < corners.objects.size() && corners.objects[i] == m) sum += row[i];
    }
    best = std::max(best, sum);
  }
  return float(best);
}

float group_dov_upper_bound(const VisibleSet& set, std::span<const ObjectId> members) {
  double sum = 0.0;
  for (ObjectId m : members) {
    auto it = std::lower_bound(set.objects.begin(), set.objects.end(), m);
    if (it != set.objects.end() && *it == m && !set.dov.empty()) sum += set.dov[size_t(it - set.objects.begin())];
  }
  return float(std::min(sum, 1.0));
}

}  // namespace cellwalk
