// `cellwalk bench visibility` (issue 4, "Storage and speed"): the engines of HDoV thesis §5.5
// and vLOD §5 measured side by side; see visibility_report.hpp for what is measured.
#include "experiments/visibility/visibility_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <sys/resource.h>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/precompute/conservative_visibility.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/store/world_file.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"
#include "experiments/common/bench_world.hpp"
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

WorldCase make_world(const std::string& name, const bench::WorkDir& dir, const bench::GeneratedScene& scene) {
  WorldCase c{name, dir.file(name + ".cww")};
  const BuildReport built = bench::make_bench_world(scene, {}, dir.file(name + ".cwscene"), c.world_file);
  c.objects = built.objects;
  c.triangles = built.triangles;
  return c;
}

PlantParams plant(int units, double detail) { return {.units_x = units, .units_z = units, .detail = detail}; }

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

// The report's tables, as the markdown shows them and the CSVs hold them.
struct Tables {
  Table engines, refine, storage, target;
};

std::string report(const VisibilityBenchParams& p, const Json& machine, const std::vector<WorldCase>& worlds,
                   const Tables& t, const std::vector<std::string>& reading, double seconds) {
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
                        t.engines) +
        "\n![tightness per checked cell](visibility/tightness.svg)\n\n";
  md += "## Conservative engine by refinement level\n\nThe same cells; level 0 is no refinement (shrinking by "
        "the whole cell, with this version's part occluders and grounding).\n\n" +
        bench::md_table({"world", "refine levels", "cells/s", "recall", "min recall", "tightness", "set % of world"},
                        t.refine) +
        "\n";
  md += "## Storage (conservative sets of a " + std::to_string(p.storage_side) + " × " +
        std::to_string(p.storage_side) + " block of neighbouring cells)\n\n" +
        bench::md_table({"world", "cells", "ids per set", "bitmask B", "gap-coded B", "stored B (gaps, Δ or bitmask)",
                         "stored / bitmask", "Δ per shared face B"},
                        t.storage) +
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
                        t.target) +
        "\n## Reading\n\n";
  for (const std::string& s : reading) md += "- " + s + "\n";
  return md;
}

// Ground truth of the checked cells `ids`: what the ID cube maps see from each.
std::vector<std::vector<ObjectId>> ground_truth(const World& world, const ViewCellPartition& cells,
                                                const std::vector<CellId>& ids, const VisibilityBenchParams& p,
                                                const std::string& name) {
  const visibility::CubeMapRenderer cube(world, p.truth_resolution);
  visibility::GroundTruthOptions gt;
  gt.points = p.truth_points;
  std::vector<std::vector<ObjectId>> truth;
  Progress progress(name + " ground truth", ids.size());
  for (CellId c : ids) {
    truth.push_back(visibility::ground_truth_visible(cube, cells.cell(c), gt));
    progress.update(truth.size());
  }
  progress.finish();
  return truth;
}

double recall_of(const EngineCheck& c) { return c.truth ? double(c.found) / double(c.truth) : 1.0; }
double tightness_of(const EngineCheck& c) { return c.truth ? double(c.set) / double(c.truth) : 1.0; }

// One world's checked cells and their ground truth, what the engines are checked against.
struct CheckedCells {
  const WorldCase& w;
  const World& world;
  const ViewCellPartition& cells;
  std::vector<CellId> ids;
  std::vector<std::vector<ObjectId>> truth;
};

// The engines table: each engine on the checked cells (dov, slow, on the first p.dov_cells).
void check_engines(const CheckedCells& c, const VisibilityBenchParams& p, Table& engines, Json& jw, LinePlot& plot) {
  for (const std::string name : {"sampling", "conservative", "dov"}) {
    const bool dov = name == "dov";
    const std::vector<CellId> some(c.ids.begin(),
                                   c.ids.begin() + std::min<ptrdiff_t>(c.ids.size(), dov ? p.dov_cells : c.ids.size()));
    const auto engine = make_engine(name, c.world);
    const EngineCheck e = check_engine(c.w.name, *engine, c.cells, some, c.truth);
    engines.push_back(check_row(e, c.w.objects));
    jw["engines"].push_back({{"engine", name}, {"cells", e.cells}, {"cells_per_second", e.cells / std::max(e.seconds, 1e-9)},
                             {"recall", recall_of(e)}, {"min_recall", e.min_recall}, {"tightness", tightness_of(e)}});
    PlotSeries series{c.w.name + " " + name, {}};
    for (size_t i = 0; i < e.tightness.size(); ++i) series.points.push_back({double(i), e.tightness[i]});
    plot.series.push_back(series);
  }
}

// The refinement table: the conservative engine at each of p.refine_levels.
void check_refinement(const CheckedCells& c, const VisibilityBenchParams& p, Table& refine, Json& jw) {
  for (int levels : p.refine_levels) {
    ConservativeParams cp;
    cp.refine_levels = levels;
    const auto engine = make_conservative_engine(c.world, cp);
    const EngineCheck e = check_engine(c.w.name, *engine, c.cells, c.ids, c.truth);
    const std::vector<std::string> row = check_row(e, c.w.objects);
    refine.push_back({c.w.name, std::to_string(levels), row[3], row[4], row[5], row[6], row[9]});
    jw["refine"].push_back({{"levels", levels}, {"tightness", tightness_of(e)}, {"min_recall", e.min_recall}});
  }
}

// The storage and target tables: the conservative engine on blocks of neighbouring cells.
void measure_blocks(const WorldCase& w, const World& world, const VisibilityBenchParams& p, const bench::WorkDir& dir,
                    Tables& t, Json& jw) {
  ConservativeParams block_params;
  block_params.threads = p.threads;
  const auto engine = make_conservative_engine(world, block_params);
  const double setup = conservative_stats(*engine)->occluder_seconds;
  const BlockRun block = run_block(world, *engine, p, dir, w.name, p.storage_side);
  const visibility::PvsSizes& s = block.sizes;
  t.storage.push_back({w.name, std::to_string(s.cells_with_sets),
                       fixed(double(s.ids) / double(std::max<uint64_t>(s.cells_with_sets, 1)), 1),
                       std::to_string(s.bitmask_bytes), std::to_string(s.full_bytes), std::to_string(s.stored_bytes),
                       fixed(double(s.stored_bytes) / double(std::max<uint64_t>(s.bitmask_bytes, 1)), 3),
                       fixed(double(s.face_delta_bytes) / double(std::max<uint64_t>(s.face_pairs, 1)), 1)});
  const bool measured = w.name == "city-1e7" && p.large_target_side > 0;
  const BlockRun timed = measured ? run_block(world, *engine, p, dir, w.name + "-target", p.large_target_side) : block;
  const double rate = double(timed.cells) / std::max(timed.seconds, 1e-9);
  const double full = setup + 4096.0 / rate;
  if (w.name.rfind("city", 0) == 0)
    t.target.push_back({w.name, std::to_string(w.triangles), std::to_string(timed.cells), fixed(rate, 3),
                        fixed(timed.cpu_seconds / std::max(timed.seconds, 1e-9), 2),
                        fixed(double(timed.cells) / std::max(timed.cpu_seconds, 1e-9), 2), fixed(setup, 1),
                        fixed(full / 60.0, 1) + " min",
                        measured ? "measured (" + fixed(timed.seconds, 1) + " s for the cells)" : "extrapolated",
                        full <= 600.0 ? "yes" : "no"});
  jw["block"] = {{"cells", timed.cells}, {"seconds", timed.seconds}, {"cells_per_second", rate},
                 {"setup_seconds", setup}, {"measured", measured}, {"cpu_seconds", timed.cpu_seconds},
                 {"extrapolated_4096_seconds", full}, {"bitmask_bytes", s.bitmask_bytes},
                 {"stored_bytes", s.stored_bytes}, {"gap_coded_bytes", s.full_bytes}};
}

// Every table's rows and the summary of one world.
Json measure_world(const WorldCase& w, const VisibilityBenchParams& p, const bench::WorkDir& dir, Tables& t,
                   LinePlot& plot) {
  const World world(w.world_file);
  const visibility::EmbreeScene scene(world);
  const auto cells = visibility::make_partition("grid:" + fixed(p.cell_size, 3), world, scene);
  CheckedCells checked{w, world, *cells, visibility::cells_to_check(*cells, uint64_t(p.checked_cells)), {}};
  checked.truth = ground_truth(world, *cells, checked.ids, p, w.name);
  Json jw = {{"world", w.name}, {"objects", w.objects}, {"triangles", w.triangles}, {"engines", Json::array()}};
  check_engines(checked, p, t.engines, jw, plot);
  check_refinement(checked, p, t.refine, jw);
  measure_blocks(w, world, p, dir, t, jw);
  return jw;
}

// The conservative engine's figures, a sentence per world.
std::vector<std::string> reading(const Json& summary, const VisibilityBenchParams& p) {
  std::vector<std::string> out;
  for (const Json& w : summary["worlds"])
    for (const Json& e : w["engines"])
      if (e["engine"] == "conservative")
        out.push_back(w["world"].get<std::string>() + ": conservative recall " + fixed(e["recall"].get<double>(), 4) +
                      " (min " + fixed(e["min_recall"].get<double>(), 4) + "), tightness " +
                      fixed(e["tightness"].get<double>(), 2) + ", 4,096 cells " +
                      (w["block"]["measured"].get<bool>() ? "measured: " : "extrapolated to ") +
                      fixed(w["block"]["extrapolated_4096_seconds"].get<double>() / 60.0, 1) + " min with setup on " +
                      std::to_string(p.threads) + " threads.");
  return out;
}

void write_csvs(const fs::path& dir, const Tables& t) {
  bench::write_csv(dir / "engines.csv",
                   {"world", "engine", "cells", "cells_per_s", "recall", "min_recall", "tightness", "mean_set",
                    "mean_truth", "set_percent_of_world"},
                   t.engines);
  bench::write_csv(dir / "refine.csv",
                   {"world", "refine_levels", "cells_per_s", "recall", "min_recall", "tightness", "set_percent_of_world"},
                   t.refine);
  bench::write_csv(dir / "storage.csv",
                   {"world", "cells", "ids_per_set", "bitmask_bytes", "gap_coded_bytes", "stored_bytes",
                    "stored_over_bitmask", "delta_per_face_bytes"},
                   t.storage);
  bench::write_csv(dir / "target.csv",
                   {"world", "triangles", "cells", "cells_per_s", "cores_used", "cells_per_cpu_s", "setup_s",
                    "cells_4096_with_setup", "how", "target_met"},
                   t.target);
}

}  // namespace

Json run_visibility_bench(const VisibilityBenchParams& p) {
  const auto start = bench::Clock::now();
  const Json machine = bench::machine_info();
  const bench::WorkDir dir(p.work_dir, "visibility");
  std::vector<WorldCase> worlds{make_world("city-1e6", dir, CityParams{.objects = p.city_objects}),
                                make_world("plant-1e6", dir, plant(p.plant_units, p.plant_detail))};
  if (p.large) {
    worlds.push_back(make_world("city-1e7", dir, CityParams{.objects = p.large_city_objects}));
    worlds.push_back(make_world("plant-1e7", dir, plant(p.large_plant_units, p.plant_detail)));
  }
  Tables tables;
  Json summary = {{"worlds", Json::array()}};
  LinePlot plot{"Tightness per checked cell (set / ground truth)", "checked cell", "tightness"};
  plot.y_min = 1.0;
  for (const WorldCase& w : worlds) summary["worlds"].push_back(measure_world(w, p, dir, tables, plot));
  const std::vector<std::string> lines = reading(summary, p);
  summary["reading"] = lines;
  const double seconds = bench::seconds_since(start);
  summary["seconds"] = seconds;
  const fs::path out(p.out_dir);
  fs::create_directories(out / "visibility");
  write_csvs(out / "visibility", tables);
  write_file_atomically((out / "visibility" / "tightness.svg").string(), render_svg(plot));
  write_file_atomically((out / "visibility.md").string(), report(p, machine, worlds, tables, lines, seconds));
  return summary;
}

}  // namespace cellwalk
