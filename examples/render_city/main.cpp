// Using cellwalk from another program: generate a city, build it into a world file, and draw
// one frame with a strategy into a PNG, headless (no window, no GPU needed: Mesa's llvmpipe).
//   render_city OUT_DIR [OBJECTS]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cellwalk/core/error.hpp"
#include "cellwalk/render/image.hpp"
#include "cellwalk/render/renderer.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/store/world.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: render_city OUT_DIR [OBJECTS]\n");
    return 2;
  }
  const std::string dir = argv[1];
  try {
    cellwalk::CityParams city;
    city.objects = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 200;
    city.landmark_fraction = 0;  // landmarks read a mesh file; plain buildings need none
    cellwalk::SceneWriter scene(dir + "/city.cwscene");
    scene.finish(cellwalk::generate_city(city, scene));
    cellwalk::build_world(dir + "/city.cwscene", dir + "/city.cww", cellwalk::BuildParams{});
    const cellwalk::World world(dir + "/city.cww");

    // The renderer needs a current OpenGL 4.5 context: headless() makes one with EGL's
    // surfaceless platform (set EGL_PLATFORM=surfaceless where no display exists).
    const auto context = cellwalk::GlContext::headless();
    cellwalk::RenderSettings settings;
    settings.backdrop = true;
    cellwalk::fit_backdrop(settings, world.info().bounds);
    cellwalk::Renderer renderer(settings);

    cellwalk::Camera camera;
    const cellwalk::Aabb& b = world.info().bounds;
    camera.position = cellwalk::Vec3(b.center().x, b.max.y + b.size().x * 0.3f, b.max.z + b.size().z * 0.3f);
    camera.pitch_deg = -35;
    cellwalk::StrategyOptions options;
    options.viewport_height_px = float(settings.height);
    const auto strategy = cellwalk::make_strategy("lod", world, options);
    const cellwalk::FrameStats stats = cellwalk::render_frame(*strategy, renderer, camera);
    cellwalk::write_png(renderer.read_color(), dir + "/city.png");
    std::printf("render_city: %zu objects in the world, %llu drawn, %llu triangles; wrote %s/city.png\n",
                world.object_count(), static_cast<unsigned long long>(stats.objects),
                static_cast<unsigned long long>(stats.triangles), dir.c_str());
    return stats.objects > 0 ? 0 : 1;
  } catch (const cellwalk::Error& e) {
    std::fprintf(stderr, "render_city: %s\n", e.what());
    return 1;
  }
}
