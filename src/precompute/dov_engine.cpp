// Degree of visibility by cubic projection, HDoV thesis §5.5.2–§5.5.3 (digest 000 §3.9):
// point DoV = Σ eq. 5.11 weights of the pixels showing the object in the ID cube map at a
// point; region DoV = max over the cell's 8 corners (eq. 5.2 sampled at the vertices, as the
// thesis does); internal nodes sum their members per corner (group_dov).
#include "precompute/dov_engine.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <deque>
#include <mutex>

#include "precompute/cell_points.hpp"
#include "precompute/ray_cube_map.hpp"

namespace cellwalk::visibility {

std::unique_ptr<CubeMapSource> make_cube_maps(DovCubes cubes, const World& world, int resolution,
                                              std::shared_ptr<const EmbreeScene> scene) {
  if (cubes == DovCubes::kExact) return std::make_unique<CubeMapRenderer>(world, resolution);
  checked_cube_resolution(resolution);  // before the costly scene
  return std::make_unique<RayCubeMap>(world, scene ? std::move(scene) : std::make_shared<const EmbreeScene>(world),
                                      resolution);
}

// The most corners kept: a few rows of a large grid (a row of 80 2D cells has 162 corners), a
// few tens of MiB at a few hundred visible objects per corner.
constexpr size_t kCachedCorners = 4096;

struct DovEngine::CornerCache {
  using Key = std::array<uint32_t, 3>;
  struct KeyHash {
    size_t operator()(const Key& k) const { return (size_t(k[0]) * 0x9E3779B97F4A7C15ull) ^ (size_t(k[1]) << 21) ^ k[2]; }
  };
  static Key key(const Vec3& p) { return {std::bit_cast<uint32_t>(p.x), std::bit_cast<uint32_t>(p.y), std::bit_cast<uint32_t>(p.z)}; }

  std::mutex mutex;
  std::unordered_map<Key, std::shared_ptr<const PointDov>, KeyHash> points;
  std::deque<Key> order;  // oldest first: the cells are computed roughly in id order
};

DovEngine::DovEngine(const World& world, const EngineOptions& options, const VisibilityEngine* prior,
                     std::shared_ptr<const EmbreeScene> scene)
    : prior_(prior),
      cube_(make_cube_maps(options.dov_cubes, world, options.dov_resolution, std::move(scene))),
      weights_(cube_pixel_weights(options.dov_resolution, options.dov_midpoint_weights)),
      smallest_(*std::min_element(weights_.begin(), weights_.end())),
      cache_(options.dov_cubes == DovCubes::kExact ? nullptr : std::make_unique<CornerCache>()) {}

DovEngine::~DovEngine() = default;

std::shared_ptr<const DovEngine::PointDov> DovEngine::point_dov(const Vec3& p) const {
  const CornerCache::Key key = CornerCache::key(p);
  if (cache_) {
    std::lock_guard lock(cache_->mutex);
    if (auto it = cache_->points.find(key); it != cache_->points.end()) return it->second;
  }
  // Two cells may compute the same corner at once: the same value, computed twice.
  auto dov = std::make_shared<PointDov>();
  for (const IdImage& face : cube_->render(p))
    for (size_t px = 0; px < face.ids.size(); ++px)
      if (face.ids[px] != kBackgroundId) (*dov)[face.ids[px] - 1] += weights_[px];
  if (cache_) {
    std::lock_guard lock(cache_->mutex);
    if (cache_->points.emplace(key, dov).second) cache_->order.push_back(key);
    if (cache_->order.size() > kCachedCorners) {
      cache_->points.erase(cache_->order.front());
      cache_->order.pop_front();
    }
  }
  return dov;
}

CornerDov DovEngine::compute_corners(const ViewCell& cell) const {
  std::vector<std::shared_ptr<const PointDov>> point;
  for (const Vec3& corner : cell_corners(cell.box)) point.push_back(point_dov(corner));
  CornerDov out;
  for (const auto& m : point)
    for (const auto& [id, dov] : *m) out.objects.push_back(id);
  std::sort(out.objects.begin(), out.objects.end());
  out.objects.erase(std::unique(out.objects.begin(), out.objects.end()), out.objects.end());
  for (const auto& m : point) {
    std::vector<float> row(out.objects.size(), 0.0f);
    for (size_t i = 0; i < out.objects.size(); ++i)
      if (auto it = m->find(out.objects[i]); it != m->end()) row[i] = float(it->second);
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
