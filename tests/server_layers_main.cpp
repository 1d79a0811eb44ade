// A program linked only with the layers a streaming server needs (core, scene, lod, store,
// index, visibility, net, the PVS streaming server and the VDR server): no OpenGL, no Embree. The build fails to link it if any of those layers
// comes to need the renderer or the precompute; tests/CMakeLists.txt also checks its dynamic
// libraries. It reads what a server would serve: a world's objects and, if stored, its sets.
#include <cstdio>
#include <exception>

#include "cellwalk/index/rtree.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/pvs_stream/pvs_server.hpp"
#include "cellwalk/systems/vdr/vdr_server.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"

int main(int argc, char** argv) {
  using namespace cellwalk;
  if (argc == 3) {  // a VDR model: served without OpenGL too
    try {
      const vdr::VdrModel model = vdr::read_vdr_file(argv[2]);
      const vdr::VdrServer server(model, {});
      std::printf("vdr server: listening on port %u\n", unsigned(server.port()));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 1;
    }
  }
  if (argc != 2 && argc != 3) {
    std::fprintf(stderr, "usage: %s WORLD.cww [MODEL.cwvdr]\n", argv[0]);
    return 2;
  }
  try {
    const World world(argv[1]);
    uint64_t triangles = 0;
    for (ObjectId id = 0; id < world.object_count(); ++id) triangles += world.lod(id, 0).triangles;
    std::printf("world %s: %zu objects, %llu triangles at level 0\n", argv[1], size_t(world.object_count()),
                (unsigned long long)triangles);
    if (world.file().has_section(visibility::kPvsSection)) {
      const visibility::StoredPvs pvs(world);
      uint64_t ids = 0;
      for (CellId c = 0; c < pvs.partition().cell_count(); ++c)
        if (auto set = pvs.set(c)) ids += set->objects.size();
      std::printf("visible sets: %zu cells, %llu ids\n", pvs.partition().cell_count(), (unsigned long long)ids);
      if (pvs.partition().kind() == "grid") {
        const pvs_stream::PvsServer server(world, {});
        std::printf("pvs server: listening on port %u\n", unsigned(server.port()));
      }
    }
    if (world.file().has_section(kRTreeSection)) std::printf("r-tree: present\n");
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
