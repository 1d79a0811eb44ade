// The world's base-colour textures as a renderer's TextureSource: every renderer that draws a
// world's objects (walk, compare, render, view, the stratified far-field baker) draws them
// textured the same way (docs/renderer.md, "Textures").
#pragma once

#include "cellwalk/render/renderer.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

// Gives `renderer` the world's textures (World::load_texture) when it has any. A texture that
// cannot be read (a damaged page or image) is drawn untextured, with one note on stderr naming
// it, rather than ending the run: the geometry is still right. REQUIRES: `world` outlives the
// renderer's use of them.
void use_world_textures(Renderer& renderer, const World& world);

}  // namespace cellwalk
