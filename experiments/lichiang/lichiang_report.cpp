// `cellwalk bench lichiang` (issue 18): Li & Chiang's four cases (seed 003, "Experimental
// Results") on our worlds; lichiang_report.hpp says what is measured and why.
#include "experiments/lichiang/lichiang_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/scene/path_generator.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/store/object_database.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/lichiang/lichiang_strategy.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"
#include "experiments/common/bench_world.hpp"
#include "precompute/pvs_builder.hpp"

namespace cellwalk {

const std::vector<std::string>& lichiang_cases() {
  static const std::vector<std::string> cases = {"lichiang:cache=none,prefetch=none", "lichiang:cache=lru,prefetch=none",
                                                 "lichiang:cache=lru,prefetch=one-step", "lichiang"};
  return cases;
}

namespace {

namespace fs = std::filesystem;
using bench::fixed;
using bench::Table;
using Json = nlohmann::ordered_json;

constexpr double kMiB = 1048576.0;
// Room for the decoded sets of the cells one frame uses (the 3 × 3 drawn and the 5 × 5 window,
// ⌈ν⌉ ahead), each as large as the largest set.
constexpr uint64_t kCellsInUse = 9 + 25;

// One world: its file with the sets, its paths, and what its budget is made of.
struct BenchWorld {
  std::string name, file;
  uint64_t objects = 0, triangles = 0;
  uint64_t geometry_bytes = 0;  // level 0 of every object, decoded
  uint64_t fixed_bytes = 0;     // the strategy's budget without its cache share
  uint64_t cells = 0;
  double pvs_seconds = 0;
  std::map<std::string, CameraPath> paths;
};

uint64_t decoded_geometry(const World& world) {
  uint64_t bytes = 0;
  for (ObjectId id = 0; id < world.object_count(); ++id)
    bytes += world.decode_level(id, 0, world.read_level(id, 0)).byte_size();
  return bytes;
}

BenchWorld prepare(const LiChiangBenchParams& p, const bench::WorkDir& dir, uint64_t objects) {
  BenchWorld w;
  w.name = std::to_string(objects) + " objects";
  const std::string base = dir.file("city" + std::to_string(objects) + ".cww");
  w.file = dir.file("city" + std::to_string(objects) + "-pvs.cww");
  bench::WorldBuild build;
  build.progress_label = "bench lichiang: build " + w.name;
  const CityParams city{.objects = objects, .landmark_fraction = p.landmark_fraction, .seed = p.city_seed};
  bench::make_bench_world(city, build, dir.file("city" + std::to_string(objects) + ".cwscene"), base);
  const World world(base);
  CameraPath all;
  for (const std::string& kind : p.path_kinds) {
    PathParams params;
    params.kind = parse_session_kind(kind);
    params.frames = p.frames;
    params.seed = p.path_seed;
    w.paths[kind] = generate_path(world.info().nav, params);
    all.frames.insert(all.frames.end(), w.paths[kind].frames.begin(), w.paths[kind].frames.end());
  }
  const auto engine = make_engine("conservative", world, EngineOptions{});
  const std::string spec = "grid:" + fixed(p.cell_size, 3);
  const visibility::EmbreeScene scene(world);
  const auto partition = visibility::cells_along(*visibility::make_partition(spec, world, scene), all, p.along_margin);
  const visibility::PvsRun run = visibility::make_pvs_run(*engine, spec, EngineOptions{}, "", p.threads);
  Progress progress("bench lichiang: pvs " + w.name, 0);
  const auto start = bench::Clock::now();
  const visibility::CellSets sets = visibility::compute_cell_sets(world, *engine, *partition, run, w.file + ".checkpoint",
                                                                  [&](uint64_t done, uint64_t) { progress.update(done); });
  w.pvs_seconds = bench::seconds_since(start);
  progress.finish();
  fs::remove(w.file + ".checkpoint");
  visibility::write_world_with_pvs(world, w.file, *partition, sets, run);
  w.cells = sets.size();
  size_t largest_set = 0;
  for (const auto& [cell, set] : sets) largest_set = std::max(largest_set, set.objects.size());

  const World with_sets(w.file);
  w.objects = with_sets.object_count();
  w.triangles = with_sets.triangle_count();
  w.geometry_bytes = decoded_geometry(with_sets);
  w.fixed_bytes = GeometryStore::fixed_bytes(with_sets, 2) + visibility::StoredPvs(with_sets).resident_bytes() +
                  kCellsInUse * (largest_set * sizeof(ObjectId) + 32);
  return w;
}

struct CaseRun {
  std::string strategy;
  double mean_ms = 0, sd_ms = 0;
  uint64_t hits = 0, misses = 0, stalls = 0, bytes_read = 0, peak = 0, prefetches = 0;
  double io_ms = 0;  // the frames' own reads (a prefetch's are the loader thread's)
  double hit_ratio() const { return hits + misses ? double(hits) / double(hits + misses) : 0.0; }
};

CaseRun walk_case(const LiChiangBenchParams& p, uint64_t budget, const World& world, const CameraPath& path,
                  const std::string& strategy_name, const std::string& objects_db, const std::string& label) {
  RenderSettings settings;
  settings.width = p.width;
  settings.height = p.height;
  settings.gpu_budget_bytes = uint64_t(p.gpu_mib * kMiB);
  Renderer renderer(settings);
  StrategyOptions options;
  options.memory_budget_bytes = budget;
  options.viewport_height_px = float(p.height);
  options.objects_db = objects_db;
  const std::unique_ptr<Strategy> strategy = make_strategy(strategy_name, world, options);
  Camera lens;
  lens.aspect = float(p.width) / float(p.height);
  Progress progress("bench lichiang: " + label, path.frames.size());
  const std::vector<FrameStats> frames = walk(path, lens, *strategy, renderer, [&](size_t done, size_t) { progress.update(done); });
  progress.finish();
  CaseRun r;
  r.strategy = strategy_name;
  std::vector<double> ms;
  for (const FrameStats& f : frames) {
    ms.push_back(f.frame_ms);
    r.hits += f.cache_hits;
    r.misses += f.cache_misses;
    r.stalls += f.stall ? 1 : 0;
    r.bytes_read += f.bytes_read;
    r.io_ms += f.io_ms;
  }
  r.mean_ms = bench::mean(ms);
  r.sd_ms = std::sqrt(bench::variance(ms));
  r.peak = strategy->peak_resident_bytes();
  if (const auto* lc = dynamic_cast<const LiChiangStrategy*>(strategy.get())) r.prefetches = lc->counters().prefetch_requests;
  return r;
}

// The (world, backend) pairs walked, in order: every world from the file, the first also from
// the other backends.
std::vector<std::pair<size_t, std::string>> backend_runs(size_t worlds, const std::vector<std::string>& backends) {
  std::vector<std::pair<size_t, std::string>> runs;
  for (size_t i = 0; i < worlds; ++i)
    for (const std::string& b : backends)
      if (b == "file" || i == 0) runs.emplace_back(i, b);
  return runs;
}

const std::vector<std::string> kCasesHeader = {"world", "backend", "cache % of world", "path", "case", "frame ms mean", "sd", "hit ratio %", "stall frames",
                                               "stall %", "MiB read", "I/O ms a miss", "prefetch requests", "peak / budget MiB"};

}  // namespace

Json run_lichiang_bench(const LiChiangBenchParams& p) {
  if (p.world_objects.empty() || p.path_kinds.empty()) fail("bench lichiang", "give at least one --objects and one --path");
  if (p.cache_fractions.empty()) fail("bench lichiang", "give at least one --cache-fraction");
  for (const double f : p.cache_fractions)
    if (!(f > 0.0 && f <= 1.0)) fail("bench lichiang", "--cache-fraction " + fixed(f, 3) + " is not in (0, 1]");
  for (const std::string& kind : p.path_kinds) parse_session_kind(kind);
  for (const std::string& b : p.backends)
    if (b != "file" && b != "sqlite") fail("bench lichiang", "--backend " + b + ": expected file or sqlite");
  const auto start = bench::Clock::now();
  const bench::WorkDir dir(p.work_dir, "lichiang");
  std::vector<BenchWorld> worlds;
  for (const uint64_t n : p.world_objects) worlds.push_back(prepare(p, dir, n));

  const std::unique_ptr<GlContext> context = GlContext::headless();
  Table rows;
  Json summary = Json::object();
  int compared = 0, beaten = 0, over_budget = 0;
  std::string target_rows;
  for (const auto& [world_index, backend] : backend_runs(worlds.size(), p.backends)) {
    const BenchWorld& w = worlds[world_index];
    const World world(w.file);
    const std::string db = backend == "sqlite" ? w.file + ".sqlite" : "";
    if (!db.empty()) build_object_database(world, db);
    const std::string name = backend == "file" ? w.name : w.name + " (" + backend + ")";
    for (const double fraction : p.cache_fractions) {
      const uint64_t budget = w.fixed_bytes + level_source_bound(world, db) + uint64_t(fraction * double(w.geometry_bytes));
      const std::string share = fixed(100 * fraction, 1);
      for (const std::string& kind : p.path_kinds) {
        std::vector<CaseRun> runs;
        for (const std::string& c : lichiang_cases())
          runs.push_back(walk_case(p, budget, world, w.paths.at(kind), c, db, name + ", " + share + " %, " + kind + ", " + c));
        for (const CaseRun& r : runs) {
          rows.push_back({w.name, backend, share, kind, r.strategy, fixed(r.mean_ms, 1), fixed(r.sd_ms, 1), fixed(100 * r.hit_ratio(), 2),
                          std::to_string(r.stalls), fixed(100.0 * double(r.stalls) / double(p.frames), 2),
                          fixed(double(r.bytes_read) / kMiB, 1), fixed(r.misses ? r.io_ms / double(r.misses) : 0.0, 3),
                          std::to_string(r.prefetches),
                          fixed(double(r.peak) / kMiB, 2) + " / " + fixed(double(budget) / kMiB, 2)});
          summary[name][share][kind][r.strategy] = {{"frame_ms", r.mean_ms}, {"sd_ms", r.sd_ms}, {"hit_ratio", r.hit_ratio()},
                                                      {"stall_frames", r.stalls}, {"bytes_read", r.bytes_read},
                                                      {"peak_bytes", r.peak}, {"budget_bytes", budget}};
          over_budget += r.peak > budget;
        }
        const CaseRun &one_step = runs[2], &hybrid = runs[3];
        const bool beats = hybrid.stalls <= one_step.stalls && hybrid.hit_ratio() >= one_step.hit_ratio() &&
                           (hybrid.stalls < one_step.stalls || hybrid.hit_ratio() > one_step.hit_ratio());
        ++compared;
        beaten += beats;
        target_rows += "| " + name + " | " + share + " | " + kind + " | " + std::to_string(one_step.stalls) + " → " +
                       std::to_string(hybrid.stalls) + " | " + fixed(100 * one_step.hit_ratio(), 2) + " → " +
                       fixed(100 * hybrid.hit_ratio(), 2) + " | " + (beats ? "yes" : "**no**") + " |\n";
      }
    }
  }
  const fs::path out = fs::path(p.out_dir), sub = out / "lichiang";
  fs::create_directories(sub);
  bench::write_csv(sub / "cases.csv", kCasesHeader, rows);

  std::string md = "# Li & Chiang: the four cases (seed 003, \"Experimental Results\")\n\n";
  md += "Generated by `" + p.command_line + "` on " + bench::utc_now() + " in " + fixed(bench::seconds_since(start) / 60.0, 1) +
        " min; machine: " + bench::machine_info().dump() + ". Every figure comes from this one run.\n\n";
  md += "Worlds: generated cities (houses and towers, landmark fraction " + fixed(p.landmark_fraction, 2) + ", seed " +
        std::to_string(p.city_seed) + "); the seed's two worlds had 128 and 370 objects. Visible sets: the conservative "
        "engine on a " + fixed(p.cell_size, 0) + " m grid, for the cells within " + fixed(p.along_margin, 0) +
        " m of the paths. Paths: " + std::to_string(p.frames) + " frames of each kind, seed " + std::to_string(p.path_seed) +
        " (the seed's were 1,068 and 1,780 steps from a path planner). Images " + std::to_string(p.width) + "×" +
        std::to_string(p.height) + " on llvmpipe; the renderer's buffer cache is held to " + fixed(p.gpu_mib, 1) +
        " MiB so the store is what caches. The budget of every case is the strategy's fixed parts (directory, room for two "
        "loads, the stored sets, the sets of the cells in use; over the sqlite backend, the object database's bound too) plus a cache share, a fraction of the world's decoded geometry; each case walks on its own, with a fresh strategy and renderer.\n\n";
  md += "| world | objects | triangles | geometry MiB | cells with sets | pvs s | fixed parts MiB |\n|---|---|---|---|---|---|---|\n";
  for (const BenchWorld& w : worlds)
    md += "| " + w.name + " | " + std::to_string(w.objects) + " | " + std::to_string(w.triangles) + " | " +
          fixed(double(w.geometry_bytes) / kMiB, 1) + " | " + std::to_string(w.cells) + " | " + fixed(w.pvs_seconds, 1) + " | " +
          fixed(double(w.fixed_bytes) / kMiB, 2) + " |\n";
  md += "\nThe seed (its second world, 370 objects, 1,780 steps; a Pentium II, a DBMS over JDBC): frame time 305.6 / 97.2 / "
        "97.7 / 103.8 ms (sd 133.6 / 52.6 / 51.8 / 46), hit ratio — / 90.9 / 90.8 / 95.2 % for cases 1–4.\n\n";
  md += "## The cases\n\n" + bench::md_table(kCasesHeader, rows, bench::Align::kFigures);
  md += "\nBackend: where the store reads objects, `file` (the world file's pages) or `sqlite` (the object database of "
        "`cellwalk db`, one prepared query per object, as the seed's DBMS over JDBC; the first world only). I/O ms a miss: the "
        "frames' own read time over their misses (a prefetch reads on the loader thread).\n";
  md += "\nA stall frame read geometry it had to draw. The hit ratio is of the store's requests for geometry to draw "
        "(a prefetched object found resident is a hit; one still loading, a miss).\n";
  md += "\n## Target: hybrid + relevance against LRU + one-step, on stall frames and hit ratio\n\n"
        "| world | cache % | path | stall frames (one-step → hybrid) | hit ratio % | beats on both |\n|---|---|---|---|---|---|\n" + target_rows;
  md += "\nBeats on both (neither worse, one better): " + std::to_string(beaten) + " of " + std::to_string(compared) +
        ". Walks whose strategy peak passed its budget: " + std::to_string(over_budget) + ".\n";
  write_file_atomically((out / "lichiang.md").string(), md);
  summary["beaten"] = beaten;
  summary["compared"] = compared;
  summary["over_budget"] = over_budget;
  return summary;
}

}  // namespace cellwalk
