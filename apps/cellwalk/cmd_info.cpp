// cellwalk info: what a scene file holds.
#include <cstdio>

#include <nlohmann/json.hpp>

#include "cellwalk/scene_file.hpp"
#include "commands.hpp"

namespace cellwalk::app {

void register_info(CLI::App& root) {
  auto* cmd = root.add_subcommand("info", "Print what a scene file holds");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("file", *file, "Scene file (.cwscene)")->required();
  cmd->add_flag("--json", *json, "Machine-readable output");
  cmd->callback([file, json] {
    SceneReader scene(*file);
    const SceneInfo& info = scene.info();
    uint64_t record_bytes = 0;
    for (ObjectId id = 0; id < scene.object_count(); ++id) record_bytes += scene.entry(id).size;
    const Vec3 lo = info.bounds.min, hi = info.bounds.max;
    if (*json) {
      nlohmann::ordered_json j = {{"file", *file},          {"generator", info.generator},
                                  {"seed", info.seed},      {"objects", scene.object_count()},
                                  {"triangles", scene.triangle_count()}, {"record_bytes", record_bytes},
                                  {"bounds", {{lo.x, lo.y, lo.z}, {hi.x, hi.y, hi.z}}},
                                  {"nav_nodes", info.nav.nodes.size()}, {"nav_edges", info.nav.edges.size()}};
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    std::printf("scene %s\n  generator  %s (seed %llu)\n  objects    %zu\n  triangles  %llu\n"
                "  bytes      %llu in object records\n  bounds     (%.1f %.1f %.1f) .. (%.1f %.1f %.1f)\n"
                "  navigation %zu nodes, %zu edges\n",
                file->c_str(), info.generator.c_str(), (unsigned long long)info.seed, scene.object_count(),
                (unsigned long long)scene.triangle_count(), (unsigned long long)record_bytes, lo.x, lo.y,
                lo.z, hi.x, hi.y, hi.z, info.nav.nodes.size(), info.nav.edges.size());
  });
}

}  // namespace cellwalk::app
