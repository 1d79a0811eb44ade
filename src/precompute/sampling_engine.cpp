// Sampling visibility with Embree rays (vLOD §5 as sampling; HDoV thesis §5.5.2 sample points):
// from the cell's corners, face centres, centre and random points inside and on its faces, a
// ray in each of `rays_per_point` directions spread evenly over the sphere, and rays aimed at
// random points of every object's box; the union of first hits is the visible set. It may miss
// objects (docs/visibility.md).
#include "precompute/sampling_engine.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include <glm/gtc/quaternion.hpp>

#include "precompute/cell_points.hpp"

namespace cellwalk::visibility {

namespace {

// Evenly spread unit vectors (the Fibonacci spiral): no clusters, no holes at the poles.
std::vector<Vec3> fibonacci_sphere(int n) {
  std::vector<Vec3> out;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double y = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - y * y), phi = golden * i;
    out.emplace_back(float(r * std::cos(phi)), float(y), float(r * std::sin(phi)));
  }
  return out;
}

// A uniformly random rotation (Shoemake), so different points fill each other's gaps.
glm::quat random_rotation(Random& rng) {
  const double u1 = rng.uniform(), u2 = rng.uniform() * 2 * M_PI, u3 = rng.uniform() * 2 * M_PI;
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  return glm::quat(float(b * std::cos(u3)), float(a * std::sin(u2)), float(a * std::cos(u2)), float(b * std::sin(u3)));
}

uint64_t box_seed(const Aabb& box, uint64_t seed) {
  uint64_t h = seed;
  for (int a = 0; a < 3; ++a)
    h = h * 0x100000001B3ull ^ std::bit_cast<uint32_t>(box.min[a]) ^ uint64_t(std::bit_cast<uint32_t>(box.max[a])) << 32;
  return h;
}

}  // namespace

SamplingEngine::SamplingEngine(const World& world, const EngineOptions& options,
                               std::shared_ptr<const EmbreeScene> scene)
    : world_(world),
      options_(options),
      scene_(scene ? std::move(scene) : std::make_shared<const EmbreeScene>(world)),
      directions_(fibonacci_sphere(options.rays_per_point)) {
  far_ = 2.0f * glm::length(world.info().bounds.size()) + 1.0f;
}

VisibleSet SamplingEngine::compute(const ViewCell& cell) const {
  Random rng(box_seed(cell.box, options_.seed));
  std::vector<Vec3> points = cell_corners(cell.box);
  for (const Vec3& p : cell_face_centres_and_centre(cell.box)) points.push_back(p);
  for (const Vec3& p : cell_random_points(cell.box, options_.sample_points, rng)) points.push_back(p);
  std::vector<ObjectId> hits;
  for (const Vec3& p : points) {
    const glm::quat q = random_rotation(rng);
    for (const Vec3& d : directions_)
      if (auto id = scene_->first_hit(p, q * d, far_)) hits.push_back(*id);
    for (ObjectId target = 0; target < world_.object_count(); ++target) {
      const Aabb& b = world_.object(target).bounds;
      for (int k = 0; k < options_.aimed_rays_per_object; ++k) {
        const Vec3 at(rng.uniform(b.min.x, b.max.x), rng.uniform(b.min.y, b.max.y), rng.uniform(b.min.z, b.max.z));
        if (at == p) continue;
        if (auto id = scene_->first_hit(p, glm::normalize(at - p), far_)) hits.push_back(*id);
      }
    }
    // Keep the list short: most rays hit the same few objects.
    std::sort(hits.begin(), hits.end());
    hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
  }
  return VisibleSet{std::move(hits), {}};
}

}  // namespace cellwalk::visibility
