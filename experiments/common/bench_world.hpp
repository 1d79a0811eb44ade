// The world a `cellwalk bench <name>` measures (DESIGN.md "Measuring"): a generated scene, city
// or plant, built into a world file. One helper for every bench, so that what differs between
// their worlds is the parameters each passes, not copies of the generate-and-build steps.
#pragma once

#include <cstdint>
#include <string>
#include <variant>

#include "cellwalk/scene/generators.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk::bench {

// The generator and its parameters.
using GeneratedScene = std::variant<CityParams, PlantParams, StratifiedCityParams>;

// How the world is built from the scene.
struct WorldBuild {
  BuildParams params;
  uint32_t rtree_fanout = 0;   // > 0: also the R-tree section REVIEW queries, of this fan-out M
  std::string progress_label;  // the build's progress line on stderr; empty = none
};

// Writes `scene` to `scene_file`; with a non-empty `progress_label`, a progress line per object
// generated (a large city takes minutes to generate).
void write_generated_scene(const GeneratedScene& scene, const std::string& scene_file,
                           const std::string& progress_label = "");

// build_world of `scene_file` into `world_file` as `build` says.
BuildReport build_bench_world(const std::string& scene_file, const std::string& world_file, const WorldBuild& build);

// Generates `scene` into `scene_file`, builds it into `world_file` and removes the scene file.
BuildReport make_bench_world(const GeneratedScene& scene, const WorldBuild& build, const std::string& scene_file,
                             const std::string& world_file);

}  // namespace cellwalk::bench
