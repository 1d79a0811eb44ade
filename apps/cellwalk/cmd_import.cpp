// `cellwalk import FILE... -o OUT.cwscene [--scale S] [--up y|z] [--offset X,Y,Z] [--place grid]
// [--patch-triangles N] [--memory MIB] [--stream] [--temp-dir DIR] [--obj X.obj] [--gltf X.gltf] [--json]`: reads model files (OBJ, PLY,
// OFF, glTF/GLB) one at a time into a scene file (a PLY larger than memory streamed), places them, splits large meshes into
// patches, optionally also exports OBJ/glTF for inspection, and gives the scene a walkable
// loop around the models.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/process_memory.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

namespace {

struct ImportOptions {
  std::vector<std::string> inputs;
  std::string output;
  std::string obj;
  std::string gltf;
  bool json = false;
  Placement placement;
  std::string up = "y";
  std::vector<float> offset;
  std::string place = "as-is";
  size_t patch_triangles = 16384;
  double memory_mib = 1024;
  bool stream = false;
  std::string temp_dir;
};

// --place grid: models side by side in rows of ceil(sqrt(n)), each standing on y = 0, a fifth
// of its footprint apart. Only the model being read is known: each advances the cursor.
class GridPlacer {
 public:
  explicit GridPlacer(size_t models) : per_row_(size_t(std::ceil(std::sqrt(double(models))))) {}
  // The translation that puts a model with these bounds at the next place.
  Vec3 next(const Aabb& b) {
    if (placed_ > 0 && placed_ % per_row_ == 0) {
      z_ += row_depth_ * 1.2f;
      x_ = 0.0f;
      row_depth_ = 0.0f;
    }
    const Vec3 size = b.size();
    const Vec3 move(x_ - b.min.x, -b.min.y, z_ - b.min.z);
    x_ += size.x + 0.2f * std::max(size.x, size.z);
    row_depth_ = std::max(row_depth_, size.z);
    ++placed_;
    return move;
  }

 private:
  size_t per_row_;
  size_t placed_ = 0;
  float x_ = 0.0f, z_ = 0.0f, row_depth_ = 0.0f;
};

// The model's objects placed: turned, scaled, moved onto the grid when asked, then offset.
void place_model(std::vector<Object>& objects, const ImportOptions& opt, GridPlacer& grid) {
  Placement turn = opt.placement;
  turn.offset = Vec3(0.0f);
  const Mat4 m = placement_matrix(turn);
  Aabb bounds;
  for (Object& o : objects) {
    place(o, m);
    bounds.extend(o.bounds);
  }
  Vec3 move = opt.placement.offset;
  if (opt.place == "grid" && !bounds.empty()) move += grid.next(bounds);
  if (move == Vec3(0.0f)) return;
  const Mat4 t = glm::translate(Mat4(1.0f), move);
  for (Object& o : objects) place(o, t);
}

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

// Counts and bounds of what went into the scene, as objects are added.
struct ImportTally {
  SceneCounts counts;
  Aabb bounds;
  uint64_t skipped = 0, split = 0, textures = 0, streamed = 0;

  void add(Object& object, ObjectSink& out) {
    // Ids stay dense over the objects kept.
    object.id = static_cast<ObjectId>(counts.objects);
    bounds.extend(object.bounds);
    counts.count(object);
    out.add(object);
  }
};

// A model larger than memory: read into scratch files and handed on patch by patch, placed as
// place_model places a model read whole.
void import_streamed(const std::string& file, const ImportOptions& opt, GridPlacer& grid, ObjectSink& out,
                     ImportTally& tally) {
  Placement turn = opt.placement;
  turn.offset = Vec3(0.0f);
  StreamLimits limits;
  limits.memory_bytes = uint64_t(opt.memory_mib * 1024 * 1024);
  limits.patch_triangles = opt.patch_triangles;
  limits.temp_dir = opt.temp_dir.empty() ? std::filesystem::absolute(opt.output).parent_path().string() : opt.temp_dir;
  StreamedModel model(file, placement_matrix(turn), limits);
  ++tally.streamed;
  if (model.triangle_count() == 0) {  // a point cloud, as read whole: skipped
    ++tally.skipped;
    return;
  }
  Vec3 move = opt.placement.offset;
  if (opt.place == "grid") move += grid.next(model.bounds());
  uint64_t patches = 0;
  model.patches(move, [&](Object& patch) {
    tally.add(patch, out);
    ++patches;
  });
  tally.split += patches > 1;
}

void run_import(const ImportOptions& opt) {
  const uint64_t baseline = current_rss_bytes();
  refuse_same_files(opt.inputs, {opt.output, opt.obj, opt.gltf});
  SceneWriter scene(opt.output);
  std::unique_ptr<ObjWriter> obj = opt.obj.empty() ? nullptr : std::make_unique<ObjWriter>(opt.obj);
  std::unique_ptr<GltfWriter> gltf =
      opt.gltf.empty() ? nullptr : std::make_unique<GltfWriter>(opt.gltf);
  std::vector<ObjectSink*> sinks = {&scene};
  if (obj) sinks.push_back(obj.get());
  if (gltf) sinks.push_back(gltf.get());
  TeeSink out(sinks);

  ImportTally tally;
  const SceneCounts& counts = tally.counts;
  GridPlacer grid(opt.inputs.size());
  // One file at a time: only the model being read is in memory (a part of it, when streamed).
  for (const std::string& file : opt.inputs) {
    if (opt.stream || streams_within(file, uint64_t(opt.memory_mib * 1024 * 1024), opt.patch_triangles > 0)) {
      import_streamed(file, opt, grid, out, tally);
      continue;
    }
    ImportedModel model = import_model(file);
    std::vector<Object>& objects = model.objects;
    place_model(objects, opt, grid);
    // The model's textures are numbered from 0; in the scene they follow the earlier models'.
    const uint32_t first_texture = uint32_t(tally.textures);
    for (const TextureImage& texture : model.textures) out.add_texture(texture);
    tally.textures += model.textures.size();
    for (Object& o : objects)
      if (o.mesh.texture != kNoTexture) o.mesh.texture += first_texture;
    for (Object& read : objects) {
      // A point cloud has nothing to draw.
      if (read.mesh.triangle_count() == 0) {
        ++tally.skipped;
        continue;
      }
      std::vector<Object> patches = opt.patch_triangles > 0 ? split_into_patches(std::move(read), opt.patch_triangles)
                                                           : std::vector<Object>{std::move(read)};
      tally.split += patches.size() > 1;
      for (Object& object : patches) tally.add(object, out);
    }
  }
  if (counts.objects == 0) fail("import", "the input files hold no triangles");

  SceneInfo info;
  info.generator = "import";
  info.nav = loop_around(tally.bounds);
  scene.finish(info);
  if (obj) obj->finish();
  if (gltf) gltf->finish();

  if (opt.json) {
    nlohmann::ordered_json j = {{"inputs", opt.inputs}, {"output", opt.output}, {"objects", counts.objects},
                        {"triangles", counts.triangles}, {"vertices", counts.vertices},
                        {"bytes", counts.bytes},     {"skipped_without_triangles", tally.skipped},
                        {"split_into_patches", tally.split}, {"textures", tally.textures},
                        {"streamed", tally.streamed}, {"memory_bytes", uint64_t(opt.memory_mib * 1024 * 1024)},
                        {"baseline_rss_bytes", baseline}, {"peak_rss_bytes", peak_rss_bytes()}};
    print_json("import", j);
  } else {
    std::printf("imported %llu objects, %llu triangles, %llu bytes", static_cast<unsigned long long>(counts.objects),
                static_cast<unsigned long long>(counts.triangles), static_cast<unsigned long long>(counts.bytes));
    if (tally.split > 0) std::printf(" (%llu large meshes split into patches of at most %zu triangles)", static_cast<unsigned long long>(tally.split), opt.patch_triangles);
    if (tally.textures > 0) std::printf(", %llu textures", static_cast<unsigned long long>(tally.textures));
    if (tally.streamed > 0)
      std::printf(", %llu streamed within %.0f MiB (process peak %.1f MiB, %.1f MiB at start)",
                  static_cast<unsigned long long>(tally.streamed), opt.memory_mib, peak_rss_bytes() / 1048576.0,
                  baseline / 1048576.0);
    std::printf("\n");
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
  cmd->add_option("--scale", opt->placement.scale, "Multiply coordinates by this (e.g. 0.001 for a model in millimetres)")
      ->capture_default_str()->check(number_in(0, 1e6, true));
  cmd->add_option("--up", opt->up, "The models' up axis: y (glTF, most games) or z (CAD, many scans); turned to +y")
      ->capture_default_str()->check(CLI::IsMember({"y", "z"}));
  cmd->add_option("--offset", opt->offset, "Move the models by X,Y,Z after scaling")->expected(3)->delimiter(',');
  cmd->add_option("--place", opt->place, "as-is: models keep their coordinates; grid: side by side on the ground, one per file")
      ->capture_default_str()->check(CLI::IsMember({"as-is", "grid"}));
  cmd->add_option("--patch-triangles", opt->patch_triangles,
                  "Split meshes larger than this into spatial patches of at most this many triangles, so that culling and "
                  "LOD work on parts of one big mesh (0: never split)")
      ->capture_default_str()->check(integer_in(0, 1 << 30));
  cmd->add_option("--memory", opt->memory_mib,
                  "MiB a model read streamed may take beyond the program's own; PLY and OFF files whose import in memory "
                  "could exceed it (over a quarter of it in size) are read streamed, and any file over 2 GiB but glTF")
      ->capture_default_str()->check(number_in(32, 1 << 20));
  cmd->add_flag("--stream", opt->stream, "Read every model streamed, within --memory (PLY, OFF, and OBJ as one mesh without its groups and materials)");
  cmd->add_option("--temp-dir", opt->temp_dir,
                  "Folder for a streamed model's scratch files (28 B a vertex and 108 B a triangle of disk, 96 B more a "
                  "triangle for each further partition step; default: the output's folder)");
  cmd->add_flag("--json", opt->json, "Print the counts as JSON");
  cmd->callback([opt] {
    opt->placement.z_up = opt->up == "z";
    if (!opt->offset.empty()) {
      for (float v : opt->offset)
        if (!std::isfinite(v) || std::abs(v) > 1e7f) fail("--offset", "each of X,Y,Z must be a number within ±1e7 m");
      opt->placement.offset = Vec3(opt->offset[0], opt->offset[1], opt->offset[2]);
    }
    run_import(*opt);
  });
}

}  // namespace cellwalk::app
