// Li & Chiang's viewpoint configurations (seed 003, "Visibility Pre-computation";
// cellwalk/systems/lichiang/configurations.hpp).
#include "cellwalk/systems/lichiang/configurations.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace cellwalk::lichiang {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// `a` brought into [0, 2π).
double wrap(double a) {
  a = std::fmod(a, kTwoPi);
  return a < 0.0 ? a + kTwoPi : a;
}

// `a` brought into (−π, π].
double signed_wrap(double a) {
  a = wrap(a);
  return a > std::numbers::pi ? a - kTwoPi : a;
}

}  // namespace

bool YawRange::contains(double yaw) const { return all || wrap(yaw - lo) <= wrap(hi - lo); }

bool YawRange::meets(const YawRange& other) const {
  return all || other.all || contains(other.lo) || other.contains(lo);
}

double yaw_of(double x, double z) { return wrap(std::atan2(-x, -z)); }

YawRange directions_between(const Aabb& from, const Aabb& to) {
  // The directions are those of the points of the difference box to − from; it is convex, so
  // when it leaves out the origin its directions span less than π and its corners bound them.
  const double x0 = double(to.min.x) - from.max.x, x1 = double(to.max.x) - from.min.x;
  const double z0 = double(to.min.z) - from.max.z, z1 = double(to.max.z) - from.min.z;
  if (x0 <= 0.0 && x1 >= 0.0 && z0 <= 0.0 && z1 >= 0.0) return {0.0, 0.0, true};
  const double centre = yaw_of(0.5 * (x0 + x1), 0.5 * (z0 + z1));
  double lo = 0.0, hi = 0.0;
  for (const auto& [x, z] : std::array<std::array<double, 2>, 4>{{{x0, z0}, {x0, z1}, {x1, z0}, {x1, z1}}}) {
    if (x == 0.0 && z == 0.0) continue;  // a corner at the origin adds no direction of its own
    const double d = signed_wrap(yaw_of(x, z) - centre);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  return {wrap(centre + lo), wrap(centre + hi), false};
}

std::optional<double> yaw_half_extent(const Camera& camera) {
  const double half_y = std::tan(glm::radians(double(camera.fov_y_deg)) / 2.0);
  const double half_x = half_y * camera.aspect;
  const Vec3 f = camera.forward(), r = camera.right(), u = camera.up();
  const double yaw = glm::radians(double(camera.yaw_deg));
  double extent = 0.0;
  // The image's yaws are bounded by its corners unless the vertical pierces it; then all.
  for (const double sx : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0}) {
      const double x = f.x + sx * half_x * r.x + sy * half_y * u.x;
      const double z = f.z + sx * half_x * r.z + sy * half_y * u.z;
      if (std::hypot(x, z) < 1e-9) return std::nullopt;
      extent = std::max(extent, std::abs(signed_wrap(yaw_of(x, z) - yaw)));
    }
  const double up = std::abs(double(camera.pitch_deg)) + double(camera.fov_y_deg) / 2.0;
  if (up >= 90.0 || extent >= std::numbers::pi / 2.0 + 1e-9) return std::nullopt;
  return extent;
}

int sector_of(double yaw, int sectors) { return std::min(sectors - 1, int(wrap(yaw) / kTwoPi * sectors)); }

YawRange sector_range(int sector, int spread, int sectors, std::optional<double> margin) {
  const double width = kTwoPi / sectors;
  if (!margin || 2 * spread + 1 >= sectors || (2 * spread + 1) * width + 2.0 * *margin >= kTwoPi)
    return {0.0, 0.0, true};
  return {wrap((sector - spread) * width - *margin), wrap((sector + spread + 1) * width + *margin), false};
}

}  // namespace cellwalk::lichiang
