// The world's textures as a renderer's TextureSource (strategy/world_textures.hpp).
#include "cellwalk/strategy/world_textures.hpp"

#include <cstdio>

#include "cellwalk/core/error.hpp"

namespace cellwalk {

void use_world_textures(Renderer& renderer, const World& world) {
  if (world.texture_count() == 0) return;
  renderer.set_texture_source([&world](uint32_t index, uint32_t max_side) -> std::optional<Texture> {
    try {
      return world.load_texture(index, max_side);
    } catch (const Error& e) {
      std::fprintf(stderr, "note: %s; its meshes are drawn untextured (rebuild the world)\n", e.what());
      return std::nullopt;
    }
  });
}

}  // namespace cellwalk
