#include "cellwalk/core/camera.hpp"

#include <gtest/gtest.h>

#include "cellwalk/core/random.hpp"

namespace cellwalk {
namespace {

bool in_clip_volume(const Camera& camera, const Vec3& p) {
  Vec4 c = camera.view_projection() * Vec4(p, 1.0f);
  return c.w > 0 && std::abs(c.x) <= c.w && std::abs(c.y) <= c.w && std::abs(c.z) <= c.w;
}

TEST(Camera, ForwardMatchesYawConvention) {
  Camera c;
  EXPECT_NEAR(glm::distance(c.forward(), Vec3(0, 0, -1)), 0.0f, 1e-6f);
  c.yaw_deg = 90;
  EXPECT_NEAR(glm::distance(c.forward(), Vec3(-1, 0, 0)), 0.0f, 1e-6f);
  c.yaw_deg = 0;
  c.pitch_deg = 90;
  EXPECT_NEAR(glm::distance(c.forward(), Vec3(0, 1, 0)), 0.0f, 1e-6f);
}

TEST(Camera, PointAheadIsAtScreenCentre) {
  Camera c;
  c.position = Vec3(3, 2, 1);
  c.yaw_deg = 33;
  c.pitch_deg = -12;
  Vec4 clip = c.view_projection() * Vec4(c.position + 10.0f * c.forward(), 1.0f);
  EXPECT_NEAR(clip.x / clip.w, 0.0f, 1e-5f);
  EXPECT_NEAR(clip.y / clip.w, 0.0f, 1e-5f);
}

// Oracle: sample points in each box; a box with a sampled point inside the clip volume must
// not be classified outside, and a box classified inside must have all samples inside.
TEST(Frustum, ClassifyAgreesWithPointSamplingOracle) {
  Random rng(3);
  Camera cam;
  cam.far_plane = 200;
  int outside = 0, inside = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    cam.position = Vec3(rng.uniform(-5, 5), rng.uniform(0, 3), rng.uniform(-5, 5));
    cam.yaw_deg = static_cast<float>(rng.uniform(-180, 180));
    cam.pitch_deg = static_cast<float>(rng.uniform(-60, 60));
    Aabb box;
    Vec3 c(rng.uniform(-100, 100), rng.uniform(-20, 20), rng.uniform(-100, 100));
    Vec3 h(rng.uniform(0.1, 20), rng.uniform(0.1, 20), rng.uniform(0.1, 20));
    box.min = c - h;
    box.max = c + h;
    const Containment k = Frustum(cam).classify(box);
    bool any = false, all = true;
    for (int s = 0; s < 200; ++s) {
      Vec3 p = box.min + Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * (box.max - box.min);
      bool in = in_clip_volume(cam, p);
      any |= in;
      all &= in;
    }
    for (int corner = 0; corner < 8; ++corner) {
      Vec3 p{(corner & 1) ? box.max.x : box.min.x, (corner & 2) ? box.max.y : box.min.y,
             (corner & 4) ? box.max.z : box.min.z};
      bool in = in_clip_volume(cam, p);
      any |= in;
      all &= in;
    }
    if (any) {
      EXPECT_NE(k, Containment::kOutside) << "trial " << trial;
    }
    if (k == Containment::kInside) {
      EXPECT_TRUE(all) << "trial " << trial;
    }
    outside += k == Containment::kOutside;
    inside += k == Containment::kInside;
  }
  EXPECT_GT(outside, 200);  // the test exercised both answers
  EXPECT_GT(inside, 5);
}

}  // namespace
}  // namespace cellwalk
