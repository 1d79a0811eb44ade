// cellwalk generate: streams a generated world into a scene file (and optionally OBJ / glTF
// for inspection), printing what it wrote.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"
#include "json_output.hpp"

namespace cellwalk::app {
namespace {

struct Output {
  std::string scene, obj, gltf;
  bool json = false;
};

// Counts each object and advances the progress line before passing it on.
class CountingSink : public ObjectSink {
 public:
  CountingSink(ObjectSink& next, Progress& progress) : next_(next), progress_(progress) {}
  void add(const Object& object) override {
    counts.count(object);
    progress_.update(counts.objects);
    next_.add(object);
  }
  SceneCounts counts;

 private:
  ObjectSink& next_;
  Progress& progress_;
};

// Refuses, before anything is written, a world of more objects than kMaxObjects, estimated from
// the parameters (the generators themselves would run for hours and fill the disk).
void refuse_too_many(const std::string& what, double estimated_objects) {
  if (estimated_objects > double(kMaxObjects))
    fail(what, "these parameters make about " + std::to_string(uint64_t(estimated_objects)) +
                   " objects, more than the most a generator writes (" + std::to_string(kMaxObjects) +
                   "); use fewer or larger parts");
}

void write_world(const std::string& what, const Output& out, const std::vector<std::string>& inputs,
                 uint64_t expected_objects, const std::function<SceneInfo(ObjectSink&)>& generate) {
  refuse_same_files(inputs, {out.scene, out.obj, out.gltf});
  const Stopwatch clock;
  SceneWriter scene(out.scene);
  std::vector<ObjectSink*> sinks{&scene};
  std::unique_ptr<ObjWriter> obj;
  std::unique_ptr<GltfWriter> gltf;
  if (!out.obj.empty()) sinks.push_back((obj = std::make_unique<ObjWriter>(out.obj)).get());
  if (!out.gltf.empty()) sinks.push_back((gltf = std::make_unique<GltfWriter>(out.gltf)).get());
  TeeSink tee(sinks);
  Progress progress(what, expected_objects);
  CountingSink counter(tee, progress);
  SceneInfo info = generate(counter);
  progress.finish();
  const size_t nav_nodes = info.nav.nodes.size(), nav_edges = info.nav.edges.size();
  scene.finish(std::move(info));
  if (obj) obj->finish();
  if (gltf) gltf->finish();
  const double seconds = clock.ms() / 1000.0;
  const SceneCounts& c = counter.counts;
  if (out.json) {
    const nlohmann::ordered_json j = {
        {"generator", what},        {"output", out.scene},    {"objects", c.objects},
        {"triangles", c.triangles}, {"vertices", c.vertices}, {"bytes", c.bytes},
        {"nav_nodes", nav_nodes},   {"nav_edges", nav_edges}, {"seconds", seconds}};
    print_json("generate", j);
    return;
  }
  std::printf("%s: %llu objects, %llu triangles, %llu bytes (raw), written to %s in %.2f s\n",
              what.c_str(), static_cast<unsigned long long>(c.objects),
              static_cast<unsigned long long>(c.triangles),
              static_cast<unsigned long long>(c.bytes), out.scene.c_str(), seconds);
}

CLI::App* add_generator(CLI::App& generate, const std::string& name, const std::string& help,
                        std::shared_ptr<Output> out) {
  CLI::App* cmd = generate.add_subcommand(name, help);
  cmd->add_option("-o,--output", out->scene, "Scene file to write (.cwscene)")->required();
  cmd->add_option("--obj", out->obj, "Also write the objects as Wavefront OBJ");
  cmd->add_option("--gltf", out->gltf,
                  "Also write the objects as glTF 2.0 (.gltf + .bin, or .glb)");
  cmd->add_flag("--json", out->json, "Print the counts as JSON");
  return cmd;
}

void register_city(CLI::App& generate, std::shared_ptr<Output> out) {
  auto p = std::make_shared<CityParams>();
  CLI::App* cmd = add_generator(
      generate, "city",
      "HDoV thesis §3.3 cityscape: houses, towers and landmark bunnies on a street grid", out);
  cmd->add_option("--objects", p->objects, "Number of objects")->capture_default_str()
      ->check(integer_in(1, int64_t(kMaxObjects)));
  cmd->add_option("--landmark-fraction", p->landmark_fraction,
                  "Fraction of objects that are landmarks")
      ->capture_default_str()
      ->check(number_in(0, 1));
  cmd->add_option("--extent", p->extent,
                  "Side of the square city in metres (0: derived from --objects)")
      ->capture_default_str()
      ->check(number_in(0, 1e6));
  cmd->add_option("--seed", p->seed, "Random seed")->capture_default_str()
      ->check(integer_in(0, INT64_MAX));
  cmd->add_option("--landmark-mesh", p->landmark_mesh,
                  "Landmark model (OFF/PLY/OBJ/glTF; default: the CGAL bunny)");
  cmd->callback([p, out] {
    write_world("city", *out, {p->landmark_mesh}, p->objects,
                [&](ObjectSink& sink) { return generate_city(*p, sink); });
  });
}

void register_stratified_city(CLI::App& generate, std::shared_ptr<Output> out) {
  auto p = std::make_shared<StratifiedCityParams>();
  CLI::App* cmd = add_generator(generate, "stratified-city",
                                "Random city of the stratified-rendering thesis, Appendix A", out);
  cmd->add_option("--max-height", p->max_height, "Maximum building height, metres")
      ->capture_default_str()
      ->check(number_in(0, 1e4, true));
  cmd->add_option("--block-length", p->block_length, "Block length (X), metres")
      ->capture_default_str()
      ->check(number_in(0, 1e4, true));
  cmd->add_option("--block-width", p->block_width, "Block width (Z), metres")
      ->capture_default_str()
      ->check(number_in(0, 1e4, true));
  cmd->add_option("--rows", p->rows_per_block, "Most building rows per block")
      ->capture_default_str()
      ->check(integer_in(1, 1000));
  cmd->add_option("--columns", p->columns_per_block, "Most building columns per row")
      ->capture_default_str()
      ->check(integer_in(1, 1000));
  cmd->add_option("--blocks-x", p->blocks_x, "Blocks along X")->capture_default_str()
      ->check(integer_in(1, 10000));
  cmd->add_option("--blocks-z", p->blocks_z, "Blocks along Z")->capture_default_str()
      ->check(integer_in(1, 10000));
  cmd->add_option("--street-width", p->street_width, "Street width, metres")->capture_default_str()
      ->check(number_in(0, 1e3, true));
  cmd->add_option("--street-height", p->street_height, "Street surface height, metres")
      ->capture_default_str()
      ->check(number_in(0, 100));
  cmd->add_option("--curb-width", p->curb_width, "Curb width, metres")->capture_default_str()
      ->check(number_in(0, 1e3));
  cmd->add_option("--curb-height", p->curb_height, "Curb height, metres")->capture_default_str()
      ->check(number_in(0, 100));
  cmd->add_option("--tree-spacing", p->tree_spacing, "Distance between trees, metres (0: no trees)")
      ->capture_default_str()
      ->check(number_in(0, 1e4));
  cmd->add_option("--seed", p->seed, "Random seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->callback([p, out] {
    // Buildings fill each block's rows and columns; trees stand along both sides of every street.
    const double blocks = double(p->blocks_x) * p->blocks_z;
    const double trees = p->tree_spacing > 0 ? blocks * 4 * (p->block_length + p->block_width) / p->tree_spacing : 0;
    refuse_too_many("stratified-city", blocks * p->rows_per_block * p->columns_per_block + trees);
    write_world("stratified-city", *out, {}, 0,
                [&](ObjectSink& sink) { return generate_stratified_city(*p, sink); });
  });
}

void register_plant(CLI::App& generate, std::shared_ptr<Output> out) {
  auto p = std::make_shared<PlantParams>();
  CLI::App* cmd =
      add_generator(generate, "plant", "Industrial plant of process units between aisles", out);
  cmd->add_option("--units-x", p->units_x, "Process units along X")->capture_default_str()
      ->check(integer_in(1, 10000));
  cmd->add_option("--units-z", p->units_z, "Process units along Z")->capture_default_str()
      ->check(integer_in(1, 10000));
  cmd->add_option("--detail", p->detail, "Scales tessellation and part counts, (0, 16]")
      ->capture_default_str()
      ->check(number_in(0, 16, true));
  cmd->add_option("--seed", p->seed, "Random seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->callback([p, out] {
    constexpr double kPlantObjectsPerUnit = 70;  // at detail 1, about proportional above (docs/generators.md)
    refuse_too_many("plant", double(p->units_x) * p->units_z * kPlantObjectsPerUnit * std::max(1.0, p->detail));
    write_world("plant", *out, {}, 0, [&](ObjectSink& sink) { return generate_plant(*p, sink); });
  });
}

void register_grid(CLI::App& generate, std::shared_ptr<Output> out) {
  auto p = std::make_shared<GridParams>();
  CLI::App* cmd =
      add_generator(generate, "grid", "Copies of one model on a lattice with lanes between", out);
  cmd->add_option("--mesh", p->mesh, "Model to copy (OFF/PLY/OBJ/glTF)")->required();
  cmd->add_option("--nx", p->nx, "Copies along X")->capture_default_str()
      ->check(integer_in(1, 100000));
  cmd->add_option("--ny", p->ny, "Layers along Y")->capture_default_str()
      ->check(integer_in(1, 100000));
  cmd->add_option("--nz", p->nz, "Copies along Z")->capture_default_str()
      ->check(integer_in(1, 100000));
  cmd->add_option("--spacing", p->spacing, "Lattice pitch (0: 1.5 x the model's size, scaled to 1)")
      ->capture_default_str()
      ->check(number_in(0, 1e6));
  cmd->add_option("--seed", p->seed, "Random seed (instance colours)")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->callback([p, out] {
    const uint64_t total = uint64_t(p->nx) * p->ny * p->nz;
    refuse_too_many("grid", double(total));
    write_world("grid", *out, {p->mesh}, total, [&](ObjectSink& sink) { return generate_grid(*p, sink); });
  });
}

void register_level(CLI::App& generate, std::shared_ptr<Output> out) {
  auto p = std::make_shared<LevelParams>();
  CLI::App* cmd = add_generator(
      generate, "level", "Indoor level of single-sided faces: rooms joined by corridors, one object per face", out);
  cmd->add_option("--rooms-x", p->rooms_x, "Rooms along X (10 m apart)")->capture_default_str()->check(integer_in(1, 1000));
  cmd->add_option("--rooms-z", p->rooms_z, "Rooms along Z")->capture_default_str()->check(integer_in(1, 1000));
  cmd->add_option("--tile", p->tile, "Faces are tiled into quads of at most this many metres (0: one quad a face)")
      ->capture_default_str()
      ->check(number_in(0, 1e3));
  cmd->add_option("--crates", p->crates, "Closed crates on each room's floor")->capture_default_str()->check(integer_in(0, 100));
  cmd->add_option("--seed", p->seed, "Random seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->callback([p, out] {
    constexpr double kFacesPerRoom = 40;  // walls split by corridor mouths, floors, ceilings
    refuse_too_many("level", double(p->rooms_x) * p->rooms_z * (kFacesPerRoom + p->crates));
    write_world("level", *out, {}, 0, [&](ObjectSink& sink) { return generate_level(*p, sink); });
  });
}

}  // namespace

void register_generate(CLI::App& root) {
  CLI::App* generate = root.add_subcommand("generate", "Generate a world into a scene file");
  generate->require_subcommand(1);
  auto out = std::make_shared<Output>();
  register_city(*generate, out);
  register_stratified_city(*generate, out);
  register_plant(*generate, out);
  register_grid(*generate, out);
  register_level(*generate, out);
}

}  // namespace cellwalk::app
