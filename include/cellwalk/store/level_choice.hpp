// Choosing a stored level of detail by its projected error from a viewpoint: the rule the `lod`
// baseline draws with, the viewer's bird's-eye view and the stratified far-field baker (seed 002
// §3.1.2 with LODs [ours]). Seeds: 001 vLOD §2.2 (digest §3.2, the corrected bound taken from
// one point); 000 HDoV thesis §5.6 (LODs chosen by projected error).
#pragma once

#include <cstdint>

#include "cellwalk/lod/screen_error.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

// The coarsest level of `object` whose worst screen-space error seen from `eye` (anywhere in
// a frustum of `lens`) is under `max_px`; level 0 when none is. Levels' errors grow with
// their index (LOD chains are ordered finest first).
uint32_t level_for_screen_error(const World& world, ObjectId id, const Vec3& eye, const Lens& lens, float max_px);

}  // namespace cellwalk
