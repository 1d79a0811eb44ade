// cellwalk info: what a scene file or a world file holds.
#include <cstdio>

#include <nlohmann/json.hpp>

#include "cellwalk/index/rtree.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/store/world.hpp"
#include "commands.hpp"
#include "json_output.hpp"

namespace cellwalk::app {
namespace {

nlohmann::ordered_json scene_json(const std::string& file) {
  SceneReader scene(file);
  const SceneInfo& info = scene.info();
  uint64_t record_bytes = 0;
  for (ObjectId id = 0; id < scene.object_count(); ++id) record_bytes += scene.entry(id).size;
  return {{"input", file},
          {"kind", "scene"},
          {"generator", info.generator},
          {"seed", info.seed},
          {"objects", scene.object_count()},
          {"triangles", scene.triangle_count()},
          {"record_bytes", record_bytes},
          {"bounds", {{info.bounds.min.x, info.bounds.min.y, info.bounds.min.z},
                      {info.bounds.max.x, info.bounds.max.y, info.bounds.max.z}}},
          {"nav_nodes", info.nav.nodes.size()},
          {"nav_edges", info.nav.edges.size()}};
}

nlohmann::ordered_json world_json(const std::string& file) {
  World world(file);
  const SceneInfo& info = world.info();
  nlohmann::ordered_json sections = nlohmann::ordered_json::array();
  for (const SectionInfo& s : world.file().sections())
    sections.push_back({{"name", s.name}, {"first_page", s.first_page}, {"bytes", s.bytes}});
  uint64_t levels = 0, stored = 0;
  std::vector<uint64_t> per_level;
  for (ObjectId id = 0; id < world.object_count(); ++id) {
    levels += world.object(id).lod_count;
    for (uint32_t l = 0; l < world.object(id).lod_count; ++l) {
      stored += world.lod(id, l).triangles;
      if (per_level.size() <= l) per_level.resize(l + 1);
      per_level[l] += world.lod(id, l).triangles;
    }
  }
  nlohmann::ordered_json rtree = nullptr;
  if (world.file().has_section(kRTreeSection)) {
    const DiskRTree tree(world);
    rtree = {{"height", tree.height()}, {"nodes", tree.node_count()}, {"max_entries", tree.max_entries()},
             {"min_entries", tree.min_entries()}, {"method", tree.method() == RTreeMethod::kStr ? "str" : "linear-insert"}};
  }
  return {{"input", file},
          {"kind", "world"},
          {"page_size", world.file().page_size()},
          {"pages", world.file().page_count()},
          {"generator", info.generator},
          {"seed", info.seed},
          {"objects", world.object_count()},
          {"triangles", world.triangle_count()},
          {"levels", levels},
          {"triangles_per_level", per_level},
          {"stored_triangles", stored},
          {"textures", world.texture_count()},
          {"bounds", {{info.bounds.min.x, info.bounds.min.y, info.bounds.min.z},
                      {info.bounds.max.x, info.bounds.max.y, info.bounds.max.z}}},
          {"nav_nodes", info.nav.nodes.size()},
          {"nav_edges", info.nav.edges.size()},
          {"rtree", rtree},
          {"sections", sections},
          {"build_params", nlohmann::ordered_json::parse(world.build_params_json(), nullptr, false)}};
}

void print_text(const nlohmann::ordered_json& j) {
  std::printf("%s %s\n", j["kind"].get<std::string>().c_str(), j["input"].get<std::string>().c_str());
  for (const auto& [key, value] : j.items()) {
    if (key == "schema" || key == "command" || key == "kind" || key == "input" || key == "sections" || key == "build_params") continue;
    std::printf("  %-20s %s\n", key.c_str(), value.dump().c_str());
  }
  if (j.contains("sections"))
    for (const auto& s : j["sections"])
      std::printf("  section %-12s first page %-8llu %llu bytes\n", s["name"].get<std::string>().c_str(),
                  (unsigned long long)s["first_page"].get<uint64_t>(), (unsigned long long)s["bytes"].get<uint64_t>());
}

}  // namespace

void register_info(CLI::App& root) {
  auto* cmd = root.add_subcommand("info", "Print what a scene file or world file holds");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("file", *file, "Scene file (.cwscene) or world file (.cww)")->required();
  cmd->add_flag("--json", *json, "Machine-readable output");
  cmd->callback([file, json] {
    const auto j = is_world_file(*file) ? world_json(*file) : scene_json(*file);
    if (*json) print_json("info", j);
    else print_text(j);
  });
}

}  // namespace cellwalk::app
