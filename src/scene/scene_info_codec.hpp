// The binary form of SceneInfo, shared by the scene file's footer and the world file's
// "scene" section (docs/format.md).
#pragma once

#include "cellwalk/scene/scene.hpp"
#include "core/bytes.hpp"

namespace cellwalk {

void put_box(ByteWriter& w, const Aabb& box);
Aabb get_box(ByteReader& r);
void encode_scene_info(ByteWriter& w, const SceneInfo& info);
// Checks node indices of the navigation edges; throws Error through `r` on damage.
SceneInfo decode_scene_info(ByteReader& r);

}  // namespace cellwalk
