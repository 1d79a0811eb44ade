// Seed 004 (Zheng), §4.6: the two camera paths of the experiments (digest §5).
#include "cellwalk/systems/vdr/vdr_paths.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "cellwalk/core/error.hpp"

namespace cellwalk::vdr {
namespace {

float mix(float a, float b, float t) { return a + (b - a) * t; }

std::vector<VdrFrame> scan_path(const Vec3& c, float r) {
  std::vector<VdrFrame> out;
  const Vec3 front(0, 0, 1), up(0, 1, 0), right(1, 0, 0);
  for (int f = 0; f < 110; ++f) out.push_back({c + front * mix(6 * r, 1.2f * r, f / 109.0f), c});
  for (int f = 0; f < 45; ++f) {
    const Vec3 h = up * mix(-0.6f * r, 0.6f * r, f / 44.0f);
    out.push_back({c + front * 1.2f * r + h, c + h});
  }
  for (int f = 0; f < 25; ++f) {
    const Vec3 w = right * mix(0.6f * r, -0.6f * r, f / 24.0f);
    out.push_back({c + front * 1.2f * r + w, c + w});
  }
  return out;
}

std::vector<VdrFrame> orbit_path(const Vec3& c, float r) {
  std::vector<VdrFrame> out;
  const auto at = [&](float angle, float distance) {
    return VdrFrame{c + distance * Vec3(std::sin(angle), 0.0f, std::cos(angle)), c};
  };
  for (int f = 0; f < 60; ++f) out.push_back(at(0, mix(6 * r, 1.8f * r, f / 59.0f)));
  const float omega = 6.0f * std::numbers::pi_v<float> / 180;
  float angle = 0;
  for (int f = 1; f <= 50; ++f) out.push_back(at(angle += omega * f / 50.0f, 1.8f * r));
  for (int f = 0; f < 84; ++f) out.push_back(at(angle += omega, 1.8f * r));
  return out;
}

}  // namespace

std::vector<VdrFrame> thesis_path(int which, const Aabb& bounds) {
  const Vec3 c = bounds.center();
  const float r = std::max(glm::length(bounds.size()) / 2, 1e-6f);
  if (which == 1) return scan_path(c, r);
  if (which == 2) return orbit_path(c, r);
  fail("--path", "path " + std::to_string(which) + " is not one of the thesis's paths 1 and 2");
}

}  // namespace cellwalk::vdr
