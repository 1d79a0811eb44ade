// `cellwalk import FILE... -o OUT.cwscene [--obj X.obj] [--gltf X.gltf] [--json]`: reads model
// files (OBJ, PLY, OFF, glTF/GLB) one at a time into a scene file, optionally also exporting
// OBJ/glTF for inspection, and gives the scene a walkable loop around the models.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "checks.hpp"
#include "commands.hpp"

namespace cellwalk::app {

namespace {

struct ImportOptions {
  std::vector<std::string> inputs;
  std::string output;
  std::string obj;
  std::string gltf;
  bool json = false;
};

// Imported models come with no navigable space; a square loop at eye height around them,
// 10% of their extent away (at least 1 m, so a flat or point-like model still gets a loop),
// gives paths and view cells something to walk.
NavGraph loop_around(const Aabb& bounds) {
  constexpr float kEyeHeight = 1.7f;
  const Vec3 margin = glm::max(bounds.size() * 0.1f, Vec3(1.0f));
  const float x0 = bounds.min.x - margin.x, x1 = bounds.max.x + margin.x;
  const float z0 = bounds.min.z - margin.z, z1 = bounds.max.z + margin.z;
  const float y = bounds.min.y + kEyeHeight;
  NavGraph nav;
  nav.nodes = {{x0, y, z0}, {x1, y, z0}, {x1, y, z1}, {x0, y, z1}};
  nav.edges = {{0, 1}, {1, 2}, {2, 3}, {3, 0}};
  return nav;
}

void run_import(const ImportOptions& opt) {
  refuse_same_files(opt.inputs, {opt.output, opt.obj, opt.gltf});
  SceneWriter scene(opt.output);
  std::unique_ptr<ObjWriter> obj = opt.obj.empty() ? nullptr : std::make_unique<ObjWriter>(opt.obj);
  std::unique_ptr<GltfWriter> gltf =
      opt.gltf.empty() ? nullptr : std::make_unique<GltfWriter>(opt.gltf);
  std::vector<ObjectSink*> sinks = {&scene};
  if (obj) sinks.push_back(obj.get());
  if (gltf) sinks.push_back(gltf.get());
  TeeSink out(sinks);

  SceneCounts counts;
  Aabb bounds;
  uint64_t skipped = 0;
  // One file at a time: only the model being read is in memory.
  for (const std::string& file : opt.inputs) {
    for (Object& object : import_model(file)) {
      // A point cloud has nothing to draw; ids stay dense over the objects kept.
      if (object.mesh.triangle_count() == 0) {
        ++skipped;
        continue;
      }
      object.id = static_cast<ObjectId>(counts.objects);
      bounds.extend(object.bounds);
      counts.count(object);
      out.add(object);
    }
  }
  if (counts.objects == 0) fail("import", "the input files hold no triangles");

  SceneInfo info;
  info.generator = "import";
  info.nav = loop_around(bounds);
  scene.finish(info);
  if (obj) obj->finish();
  if (gltf) gltf->finish();

  if (opt.json) {
    nlohmann::json j = {{"output", opt.output},      {"objects", counts.objects},
                        {"triangles", counts.triangles}, {"vertices", counts.vertices},
                        {"bytes", counts.bytes},     {"skipped_without_triangles", skipped}};
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("imported %llu objects, %llu triangles, %llu bytes\n",
                static_cast<unsigned long long>(counts.objects),
                static_cast<unsigned long long>(counts.triangles),
                static_cast<unsigned long long>(counts.bytes));
  }
}

}  // namespace

void register_import(CLI::App& root) {
  auto opt = std::make_shared<ImportOptions>();
  CLI::App* cmd = root.add_subcommand("import", "Import OBJ, PLY, OFF, glTF or GLB models into a scene file");
  cmd->add_option("files", opt->inputs, "Model files (.obj .ply .off .gltf .glb)")->required();
  cmd->add_option("-o,--output", opt->output, "Scene file to write (.cwscene)")->required();
  cmd->add_option("--obj", opt->obj, "Also export the objects as OBJ");
  cmd->add_option("--gltf", opt->gltf, "Also export the objects as glTF (.gltf or .glb)");
  cmd->add_flag("--json", opt->json, "Print the counts as JSON");
  cmd->callback([opt] { run_import(*opt); });
}

}  // namespace cellwalk::app
