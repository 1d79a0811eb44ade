// `cellwalk bench visual`: the cities, view cells, DoVs and HDoV-trees the experiments of HDoV
// thesis §5.8 run on (digest §5.1; decisions in docs/visual.md).
#include "experiments/visual/visual_world.hpp"

#include <algorithm>

#include "cellwalk/systems/visual/visual_strategy.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"
#include "experiments/common/bench_world.hpp"
#include "precompute/pvs_builder.hpp"

namespace cellwalk::visual_bench {

namespace fs = std::filesystem;

std::string build_city(const VisualBenchParams& p, uint64_t objects, const fs::path& dir, const std::string& name) {
  const std::string raw = (dir / (name + ".cww")).string();
  // REVIEW, the baseline of Exp. 3, queries the world's own R-tree (its default fan-out).
  bench::make_bench_world(CityParams{.objects = objects, .seed = p.seed},
                          {.params = {.threads = p.threads},
                           .rtree_fanout = 32,
                           .progress_label = "build " + name + " (" + std::to_string(objects) + " objects)"},
                          (dir / (name + ".cwscene")).string(), raw);
  return raw;
}

TreeWorld add_dov_and_tree(const VisualBenchParams& p, const std::string& raw, const ViewCellPartition& cells,
                           const fs::path& dir, const std::string& name) {
  TreeWorld s;
  s.world_file = (dir / (name + ".cww")).string();
  for (CellId c = 0; c < cells.cell_count(); ++c) s.dov_cells += cells.cell(c).computed() ? 1 : 0;
  {
    const World city(raw);
    EngineOptions options;
    options.dov_resolution = p.dov_resolution;
    options.dov_cubes = p.dov_cubes;
    const auto engine = make_engine("dov", city, options);
    const visibility::PvsRun run = visibility::make_pvs_run(*engine, "visual bench cells " + std::to_string(cells.cell_count()),
                                                            options, "", p.threads);
    Stopwatch watch;
    std::unique_ptr<Progress> progress;
    const auto sets = visibility::compute_cell_sets(city, *engine, cells, run, (dir / (name + ".checkpoint")).string(),
                                                    [&](uint64_t done, uint64_t total) {
                                                      if (!progress) progress = std::make_unique<Progress>("DoV per cell, " + name, total);
                                                      progress->update(done);
                                                    });
    if (progress) progress->finish();
    s.dov_seconds = watch.ms() / 1000;
    visibility::write_world_with_pvs(city, s.world_file, cells, sets, run);
  }
  s.world = std::make_unique<World>(s.world_file);
  s.tree_file = default_hdov_path(s.world_file);
  HdovBuildParams hp;
  hp.max_entries = p.fanout;
  Stopwatch watch;
  Progress progress("HDoV-tree, " + name, 0);
  s.visible_nodes = build_visual_tree(*s.world, s.tree_file, hp, [&](uint64_t d, uint64_t) { progress.update(d); }).visible_nodes();
  progress.finish();
  s.tree_seconds = watch.ms() / 1000;
  s.tree = std::make_unique<HdovTree>(*s.world, s.tree_file);
  return s;
}

float grid_cell_side(const World& city, int per_side) {
  const CellRegion region = default_cell_region(city.info().bounds, city.info().nav, true);
  return std::max(region.bounds.size().x, region.bounds.size().z) / float(per_side);
}

std::unique_ptr<ViewCellPartition> city_grid(const World& city, float side) {
  return make_grid_partition(default_cell_region(city.info().bounds, city.info().nav, true), side);
}

std::unique_ptr<ViewCellPartition> central_grid(const World& city, float side, int per_side) {
  CellRegion region = default_cell_region(city.info().bounds, city.info().nav, true);
  const Vec3 centre = region.bounds.center();
  const float half = side * float(per_side) / 2;
  region.bounds.min.x = std::max(region.bounds.min.x, centre.x - half);
  region.bounds.min.z = std::max(region.bounds.min.z, centre.z - half);
  region.bounds.max.x = std::min(region.bounds.max.x, centre.x + half);
  region.bounds.max.z = std::min(region.bounds.max.z, centre.z + half);
  return make_grid_partition(region, side);
}

std::unique_ptr<ViewCellPartition> path_grid(const World& city, const CameraPath& path, float side) {
  CellRegion region = default_cell_region(city.info().bounds, city.info().nav, true);
  Aabb box;
  for (const PathFrame& f : path.frames) box.extend(f.position);
  region.bounds.min = Vec3(box.min.x - side / 2, region.bounds.min.y, box.min.z - side / 2);
  region.bounds.max = Vec3(box.max.x + side / 2, region.bounds.max.y, box.max.z + side / 2);
  return visibility::cells_along(*make_grid_partition(region, side), path, 0.0f);
}

}  // namespace cellwalk::visual_bench
