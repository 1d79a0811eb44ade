// `cellwalk bench visibility` (issue 4, "Storage and speed"): the engines of HDoV thesis §5.5
// and vLOD §5 measured side by side; see visibility_bench.hpp for what is measured.
#include "experiments/visibility/visibility_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <sys/resource.h>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/precompute/conservative_visibility.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/store/world_file.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"
#include "experiments/common/svg_plot.hpp"
#include "precompute/embree_scene.hpp"
#include "precompute/ground_truth.hpp"
#include "precompute/pvs_builder.hpp"

namespace cellwalk {
namespace {

namespace fs = std::filesystem;
using bench::fixed;
using bench::Table;
using Json = nlohmann::ordered_json;

struct WorldCase {
  std::string name;  // "city-1e6", ...
  std::string world_file;
  uint64_t triangles = 0;
  uint64_t objects = 0;
};

WorldCase make_world(const std::string& name, const bench::WorkDir& dir, bool city, uint64_t objects, int units,
                     double detail) {
  const std::string scene = dir.file(name + ".cwscene");
  WorldCase c{name, dir.file(name + ".cww")};
  {
    SceneWriter writer(scene);
    if (city) {
      CityParams p;
      p.objects = objects;
      writer.finish(generate_city(p, writer));
    } else {
      PlantParams p;
      p.units_x = p.units_z = units;
      p.detail = detail;
      writer.finish(generate_plant(p, writer));
    }
  }
  const BuildReport built = build_world(scene, c.world_file, BuildParams{});
  fs::remove(scene);
  c.objects = built.objects;
  c.triangles = built.triangles;
  return c;
}

struct EngineCheck {
  std::string world, engine;
  int cells = 0;
  double seconds = 0;  // engine time over the cells, one thread
  uint64_t set = 0, truth = 0, found = 0;
  double min_recall = 1.0;
  std::vector<double> tightness;  // per cell
};

EngineCheck check_engine(const std::string& world_name, const VisibilityEngine& engine, const ViewCellPartition& cells,
                         const std::vector<CellId>& ids, const std::vector<std::vector<ObjectId>>& truth) {
  EngineCheck r{world_name, engine.name(), int(ids.size())};
  Progress progress(world_name + " " + engine.name(), ids.size());
  for (size_t i = 0; i < ids.size(); ++i) {
    const auto start = bench::Clock::now();
    const VisibleSet set = engine.compute(cells.cell(ids[i]));
    r.seconds += bench::seconds_since(start);
    uint64_t found = 0;
    for (ObjectId id : truth[i]) found += std::binary_search(set.objects.begin(), set.objects.end(), id);
    r.set += set.objects.size();
    r.truth += truth[i].size();
    r.found += found;
    r.min_recall = std::min(r.min_recall, truth[i].empty() ? 1.0 : double(found) / double(truth[i].size()));
    r.tightness.push_back(truth[i].empty() ? 1.0 : double(set.objects.size()) / double(truth[i].size()));
    progress.update(i + 1);
  }
  progress.finish();
  return r;
}

std::vector<std::string> check_row(const EngineCheck& c, uint64_t objects) {
  const double recall = c.truth ? double(c.found) / double(c.truth) : 1.0;
  return {c.world, c.engine, std::to_string(c.cells), fixed(c.cells / std::max(c.seconds, 1e-9), 2),
          fixed(recall, 4), fixed(c.min_recall, 4), fixed(c.truth ? double(c.set) / double(c.truth) : 1.0, 2),
          fixed(double(c.set) / std::max(c.cells, 1), 1), fixed(double(c.truth) / std::max(c.cells, 1), 1),
          fixed(100.0 * double(c.set) / std::max(c.cells, 1) / double(std::max<uint64_t>(objects, 1)), 1)};
}

// A block of side × side neighbouring cells in the middle of the world, computed on `threads`
// threads: the target's rate and the storage of neighbouring sets.
struct BlockRun {
  uint64_t cells = 0;
  double seconds = 0;
  double cpu_seconds = 0;  // of the whole process over the run: on a shared machine, cores = cpu / wall
  visibility::PvsSizes sizes;
};

// User + system CPU time of this process so far (all threads).
double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

BlockRun run_block(const World& world, const VisibilityEngine& engine, const VisibilityBenchParams& p,
                   const bench::WorkDir& dir, const std::string& name, int side) {
  CellRegion region = default_cell_region(world.info().bounds, world.info().nav, true);
  const Vec3 centre = region.bounds.center();
  const float half = 0.5f * p.cell_size * float(side);
  region.bounds.min.x = centre.x - half, region.bounds.max.x = centre.x + half;
  region.bounds.min.z = centre.z - half, region.bounds.max.z = centre.z + half;
  const visibility::EmbreeScene scene(world);
  const auto partition =
      make_grid_partition(region, p.cell_size, [&](const Aabb& box) { return scene.box_is_solid(box); });
  const visibility::PvsRun run = visibility::make_pvs_run(
      engine, "block grid:" + std::to_string(p.cell_size) + " side " + std::to_string(side), EngineOptions{}, "", p.threads);
  const std::string checkpoint = dir.file(name + ".pvs-checkpoint");
  fs::remove(checkpoint);
  Progress progress(name + " block", partition->cell_count());
  const auto start = bench::Clock::now();
  const double cpu_start = process_cpu_seconds();
  const visibility::CellSets sets = visibility::compute_cell_sets(
      world, engine, *partition, run, checkpoint, [&](uint64_t done, uint64_t) { progress.update(done); });
  BlockRun out{sets.size(), bench::seconds_since(start), process_cpu_seconds() - cpu_start};
  progress.finish();
  out.sizes = visibility::write_world_with_pvs(world, dir.file(name + "-pvs.cww"), *partition, sets, run);
  fs::remove(checkpoint);
  fs::remove(dir.file(name + "-pvs.cww"));
  return out;
}

std::string report(const VisibilityBenchParams& p, const Json& machine, const std::vector<WorldCase>& worlds,
                   const Table& engines, const Table& refine, const Table& storage, const Table& target,
                   const std::vector<std::string>& reading, double seconds) {
  std::string md = "# Visibility engines: speed, recall, tightness, storage\n\n";
  md += "Generated by `" + p.command_line + "` on " + bench::utc_now() + " in " + fixed(seconds / 60.0, 1) +
        " min. Machine: " + machine.dump() + ".\n\n";
  md += "What is measured and how to read it: docs/visibility.md and docs/conservative-visibility.md. Cells are " +
        fixed(p.cell_size, 0) + " m squares at eye height (`grid:" + fixed(p.cell_size, 0) +
        "`), checked cells spread evenly over the ids. Ground truth: ID cube maps (6 × " +
        std::to_string(p.truth_resolution) + "²) from the 8 corners and " + std::to_string(p.truth_points) +
        " random points of each cell, a lower bound of the exact set. Tightness = set / ground truth. "
        "Cells per second: engine time alone, one thread.\n\n";
  md += "## Worlds\n\n";
  Table rows;
  for (const WorldCase& w : worlds) rows.push_back({w.name, std::to_string(w.objects), std::to_string(w.triangles)});
  md += bench::md_table({"world", "objects", "triangles"}, rows) + "\n";
  md += "## Engines\n\n" +
        bench::md_table({"world", "engine", "cells", "cells/s", "recall", "min recall", "tightness", "mean set",
                         "mean truth", "set % of world"},
                        engines) +
        "\n![tightness per checked cell](visibility/tightness.svg)\n\n";
  md += "## Conservative engine by refinement level\n\nThe same cells; level 0 is no refinement (shrinking by "
        "the whole cell, with this version's part occluders and grounding).\n\n" +
        bench::md_table({"world", "refine levels", "cells/s", "recall", "min recall", "tightness", "set % of world"},
                        refine) +
        "\n";
  md += "## Storage (conservative sets of a " + std::to_string(p.storage_side) + " × " +
        std::to_string(p.storage_side) + " block of neighbouring cells)\n\n" +
        bench::md_table({"world", "cells", "ids per set", "bitmask B", "gap-coded B", "stored B (gaps, Δ or bitmask)",
                         "stored / bitmask", "Δ per shared face B"},
                        storage) +
        "\n";
  md += "## Target: conservative sets for 4,096 cells in under 10 minutes on 2 cores\n\nBlocks of neighbouring "
        "cells in the middle of the city (about as costly as any), computed on " + std::to_string(p.threads) +
        " threads. Where the block has 4,096 cells (the ~10^7-triangle city with `--large`: " +
        std::to_string(p.large_target_side) + " × " + std::to_string(p.large_target_side) +
        ") the time is **measured**; otherwise it is **extrapolated** linearly from the storage block's rate. "
        "Seconds are the cells alone; setup (decoding level 0 and deriving the occluders, once per world, on "
        "all threads) is its own column and counted in the total. Cores used = the process's CPU seconds / wall "
        "seconds over the block: below " + std::to_string(p.threads) + " means other jobs shared the machine, and "
        "cells per CPU second × " + std::to_string(p.threads) + " is the rate on " + std::to_string(p.threads) +
        " free cores.\n\n" +
        bench::md_table({"world", "triangles", "cells", "cells/s", "cores used", "cells per CPU s", "setup s",
                         "4,096 cells + setup", "how", "target met"},
                        target) +
        "\n## Reading\n\n";
  for (const std::string& s : reading) md += "- " + s + "\n";
  return md;
}

}  // namespace

Json run_visibility_bench(const VisibilityBenchParams& p) {
  const auto start = bench::Clock::now();
  const Json machine = bench::machine_info();
  const bench::WorkDir dir(p.work_dir, "visibility");
  std::vector<WorldCase> worlds{make_world("city-1e6", dir, true, p.city_objects, 0, 0),
                                make_world("plant-1e6", dir, false, 0, p.plant_units, p.plant_detail)};
  if (p.large) {
    worlds.push_back(make_world("city-1e7", dir, true, p.large_city_objects, 0, 0));
    worlds.push_back(make_world("plant-1e7", dir, false, 0, p.large_plant_units, p.plant_detail));
  }
  Table engines, refine, storage, target;
  Json summary = {{"worlds", Json::array()}};
  LinePlot plot{"Tightness per checked cell (set / ground truth)", "checked cell", "tightness"};
  plot.y_min = 1.0;
  for (const WorldCase& w : worlds) {
    const World world(w.world_file);
    const visibility::EmbreeScene scene(world);
    const auto cells = visibility::make_partition("grid:" + fixed(p.cell_size, 3), world, scene);
    const std::vector<CellId> ids = visibility::cells_to_check(*cells, uint64_t(p.checked_cells));
    std::vector<std::vector<ObjectId>> truth;
    {
      const visibility::CubeMapRenderer cube(world, p.truth_resolution);
      visibility::GroundTruthOptions gt;
      gt.points = p.truth_points;
      Progress progress(w.name + " ground truth", ids.size());
      for (CellId c : ids) {
        truth.push_back(visibility::ground_truth_visible(cube, cells->cell(c), gt));
        progress.update(truth.size());
      }
      progress.finish();
    }
    Json jw = {{"world", w.name}, {"objects", w.objects}, {"triangles", w.triangles}, {"engines", Json::array()}};
    for (const std::string name : {"sampling", "conservative", "dov"}) {
      const bool dov = name == "dov";
      const std::vector<CellId> some(ids.begin(), ids.begin() + std::min<ptrdiff_t>(ids.size(), dov ? p.dov_cells : ids.size()));
      const auto engine = make_engine(name, world);
      const EngineCheck c = check_engine(w.name, *engine, *cells, some, truth);
      engines.push_back(check_row(c, w.objects));
      jw["engines"].push_back({{"engine", name}, {"cells", c.cells}, {"cells_per_second", c.cells / std::max(c.seconds, 1e-9)},
                               {"recall", c.truth ? double(c.found) / double(c.truth) : 1.0}, {"min_recall", c.min_recall},
                               {"tightness", c.truth ? double(c.set) / double(c.truth) : 1.0}});
      PlotSeries series{w.name + " " + name, {}};
      for (size_t i = 0; i < c.tightness.size(); ++i) series.points.push_back({double(i), c.tightness[i]});
      plot.series.push_back(series);
    }
    for (int levels : p.refine_levels) {
      ConservativeParams cp;
      cp.refine_levels = levels;
      const auto engine = make_conservative_engine(world, cp);
      const EngineCheck c = check_engine(w.name, *engine, *cells, ids, truth);
      const std::vector<std::string> row = check_row(c, w.objects);
      refine.push_back({w.name, std::to_string(levels), row[3], row[4], row[5], row[6], row[9]});
      jw["refine"].push_back({{"levels", levels}, {"tightness", c.truth ? double(c.set) / double(c.truth) : 1.0},
                              {"min_recall", c.min_recall}});
    }
    ConservativeParams block_params;
    block_params.threads = p.threads;
    const auto engine = make_conservative_engine(world, block_params);
    const double setup = conservative_stats(*engine)->occluder_seconds;
    const BlockRun block = run_block(world, *engine, p, dir, w.name, p.storage_side);
    const visibility::PvsSizes& s = block.sizes;
    storage.push_back({w.name, std::to_string(s.cells_with_sets),
                       fixed(double(s.ids) / double(std::max<uint64_t>(s.cells_with_sets, 1)), 1),
                       std::to_string(s.bitmask_bytes), std::to_string(s.full_bytes), std::to_string(s.stored_bytes),
                       fixed(double(s.stored_bytes) / double(std::max<uint64_t>(s.bitmask_bytes, 1)), 3),
                       fixed(double(s.face_delta_bytes) / double(std::max<uint64_t>(s.face_pairs, 1)), 1)});
    const bool measured = w.name == "city-1e7" && p.large_target_side > 0;
    const BlockRun timed = measured ? run_block(world, *engine, p, dir, w.name + "-target", p.large_target_side) : block;
    const double rate = double(timed.cells) / std::max(timed.seconds, 1e-9);
    const double full = setup + 4096.0 / rate;
    if (w.name.rfind("city", 0) == 0)
      target.push_back({w.name, std::to_string(w.triangles), std::to_string(timed.cells), fixed(rate, 3),
                        fixed(timed.cpu_seconds / std::max(timed.seconds, 1e-9), 2),
                        fixed(double(timed.cells) / std::max(timed.cpu_seconds, 1e-9), 2), fixed(setup, 1),
                        fixed(full / 60.0, 1) + " min",
                        measured ? "measured (" + fixed(timed.seconds, 1) + " s for the cells)" : "extrapolated",
                        full <= 600.0 ? "yes" : "no"});
    jw["block"] = {{"cells", timed.cells}, {"seconds", timed.seconds}, {"cells_per_second", rate},
                   {"setup_seconds", setup}, {"measured", measured}, {"cpu_seconds", timed.cpu_seconds},
                   {"extrapolated_4096_seconds", full}, {"bitmask_bytes", s.bitmask_bytes},
                   {"stored_bytes", s.stored_bytes}, {"gap_coded_bytes", s.full_bytes}};
    summary["worlds"].push_back(jw);
  }
  std::vector<std::string> reading;
  for (const Json& w : summary["worlds"])
    for (const Json& e : w["engines"])
      if (e["engine"] == "conservative")
        reading.push_back(w["world"].get<std::string>() + ": conservative recall " + fixed(e["recall"].get<double>(), 4) +
                          " (min " + fixed(e["min_recall"].get<double>(), 4) + "), tightness " +
                          fixed(e["tightness"].get<double>(), 2) + ", 4,096 cells " +
                          (w["block"]["measured"].get<bool>() ? "measured: " : "extrapolated to ") +
                          fixed(w["block"]["extrapolated_4096_seconds"].get<double>() / 60.0, 1) + " min with setup on " +
                          std::to_string(p.threads) + " threads.");
  summary["reading"] = reading;
  const double seconds = bench::seconds_since(start);
  summary["seconds"] = seconds;
  const fs::path out(p.out_dir);
  fs::create_directories(out / "visibility");
  bench::write_csv(out / "visibility" / "engines.csv",
                   {"world", "engine", "cells", "cells_per_s", "recall", "min_recall", "tightness", "mean_set",
                    "mean_truth", "set_percent_of_world"},
                   engines);
  bench::write_csv(out / "visibility" / "refine.csv",
                   {"world", "refine_levels", "cells_per_s", "recall", "min_recall", "tightness", "set_percent_of_world"},
                   refine);
  bench::write_csv(out / "visibility" / "storage.csv",
                   {"world", "cells", "ids_per_set", "bitmask_bytes", "gap_coded_bytes", "stored_bytes",
                    "stored_over_bitmask", "delta_per_face_bytes"},
                   storage);
  bench::write_csv(out / "visibility" / "target.csv",
                   {"world", "triangles", "cells", "cells_per_s", "cores_used", "cells_per_cpu_s", "setup_s",
                    "cells_4096_with_setup", "how", "target_met"},
                   target);
  write_file_atomically((out / "visibility" / "tightness.svg").string(), render_svg(plot));
  write_file_atomically((out / "visibility.md").string(),
                        report(p, machine, worlds, engines, refine, storage, target, reading, seconds));
  return summary;
}

}  // namespace cellwalk
