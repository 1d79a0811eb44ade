#include "cellwalk/store/level_choice.hpp"

namespace cellwalk {

uint32_t level_for_screen_error(const World& world, ObjectId id, const Vec3& eye, const Lens& lens, float max_px) {
  const ObjectRecord& o = world.object(id);
  // Pixels per object unit from the eye, once per object (its trigonometry is per frame, not per level).
  const float pixels_per_unit = cell_pixels_per_unit(Aabb{eye, eye}, o.bounds, lens);
  uint32_t chosen = 0;
  for (uint32_t level = 1; level < o.lod_count; ++level) {
    const float error = world.lod(id, level).error;
    if (error > 0.0f && error * pixels_per_unit >= max_px) break;
    chosen = level;
  }
  return chosen;
}

}  // namespace cellwalk
