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
#include "cellwalk/store/level_source.hpp"
#include "cellwalk/store/object_database.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/lichiang/lichiang_strategy.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"
#include "experiments/common/bench_world.hpp"
#include "experiments/common/svg_plot.hpp"
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
  double mean_ms = 0, sd_ms = 0, prefetch_ms = 0;
  double io_ms = 0;  // the frames' own reads (a prefetch's are the loader thread's)
  uint64_t hits = 0, misses = 0, stalls = 0, bytes_read = 0, peak = 0, prefetches = 0, frames = 0;
  double hit_ratio() const { return hits + misses ? double(hits) / double(hits + misses) : 0.0; }
  double stall_share() const { return frames ? double(stalls) / double(frames) : 0.0; }
};

// Where a walk reads objects from: the world (opened through the page cache, around it, or
// slowly) and, for "sqlite", the object database beside it.
struct Storage {
  std::string label;
  WorldFile::Options options;
  std::string objects_db;
};

CaseRun walk_case(const LiChiangBenchParams& p, uint64_t budget, const World& world, const Storage& storage,
                  const CameraPath& path, const std::string& strategy_name, const std::string& label) {
  RenderSettings settings;
  settings.width = p.width;
  settings.height = p.height;
  settings.gpu_budget_bytes = uint64_t(p.gpu_mib * kMiB);
  Renderer renderer(settings);
  StrategyOptions options;
  options.memory_budget_bytes = budget;
  options.viewport_height_px = float(p.height);
  options.objects_db = storage.objects_db;
  const std::unique_ptr<Strategy> strategy = make_strategy(strategy_name, world, options);
  Camera lens;
  lens.aspect = float(p.width) / float(p.height);
  Progress progress("bench lichiang: " + label, path.frames.size());
  const std::vector<FrameStats> frames = walk(path, lens, *strategy, renderer, [&](size_t done, size_t) { progress.update(done); });
  progress.finish();
  CaseRun r;
  r.strategy = strategy_name;
  r.frames = frames.size();
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
  if (const auto* lc = dynamic_cast<const LiChiangStrategy*>(strategy.get())) {
    r.prefetches = lc->counters().prefetch_requests;
    r.prefetch_ms = lc->counters().prefetch_ms;
  }
  return r;
}

// The storage a walk reads: the world file through the OS page cache (""), around it
// ("direct": O_DIRECT, or drop-behind where the file system refuses it), around it with a
// latency before every read ("slow"), or the SQLite object database ("sqlite", built beside
// `world_file` when `build` is set).
Storage storage_of(const std::string& kind, double latency_ms, const std::string& world_file, bool build) {
  if (kind.empty()) return {"page cache", {}, ""};
  if (kind == "direct") return {"page cache bypassed", {.bypass_cache = true}, ""};
  if (kind == "slow")
    return {"bypassed, +" + fixed(latency_ms, 1) + " ms a read",
            {.bypass_cache = true, .read_latency_us = uint32_t(std::lround(latency_ms * 1000.0))}, ""};
  if (kind == "sqlite") {
    const std::string db = world_file + ".sqlite";
    if (build) build_object_database(World(world_file), db);
    return {"sqlite", {}, db};
  }
  fail("bench lichiang", "unknown --storage \"" + kind + "\" (direct, slow, sqlite)");
}

const std::vector<std::string> kCasesHeader = {"world", "storage", "cache % of world", "path", "case", "frame ms mean", "sd",
                                               "hit ratio %", "stall frames", "stall %", "MiB read", "I/O ms a miss",
                                               "prefetch requests", "peak / budget MiB"};

// The walks' tables and the target's tally, as they are run.
struct Results {
  bench::Table cases, tp;
  nlohmann::ordered_json summary = nlohmann::ordered_json::object();
  int compared = 0, beaten = 0, over_budget = 0;
  std::string target_rows;
  std::map<std::string, PlotSeries> tp_stalls, tp_hits, tp_frame;  // by cache share
};

// The fixed parts, the object database's bound over sqlite, and the cache share.
uint64_t budget_of(const BenchWorld& w, const World& world, const Storage& storage, double fraction) {
  return w.fixed_bytes + level_source_bound(world, storage.objects_db) + uint64_t(fraction * double(w.geometry_bytes));
}

void add_case_row(Results& out, const BenchWorld& w, const std::string& storage, const std::string& share, const std::string& kind,
                  const CaseRun& r, uint64_t budget) {
  out.cases.push_back({w.name, storage, share, kind, r.strategy, fixed(r.mean_ms, 1), fixed(r.sd_ms, 1), fixed(100 * r.hit_ratio(), 2),
                       std::to_string(r.stalls), fixed(100.0 * r.stall_share(), 2), fixed(double(r.bytes_read) / kMiB, 1),
                       fixed(r.misses ? r.io_ms / double(r.misses) : 0.0, 3), std::to_string(r.prefetches), fixed(double(r.peak) / kMiB, 2) + " / " + fixed(double(budget) / kMiB, 2)});
  out.summary[w.name][storage][share][kind][r.strategy] = {
      {"frame_ms", r.mean_ms}, {"sd_ms", r.sd_ms}, {"hit_ratio", r.hit_ratio()}, {"stall_frames", r.stalls},
      {"bytes_read", r.bytes_read}, {"peak_bytes", r.peak}, {"budget_bytes", budget}};
  out.over_budget += r.peak > budget;
}

// The seed's four cases on one path; the target compares case 4 with case 3.
void walk_cases(const LiChiangBenchParams& p, const BenchWorld& w, const World& world, const Storage& storage, double fraction,
                const std::string& kind, Results& out) {
  const uint64_t budget = budget_of(w, world, storage, fraction);
  const std::string share = fixed(100 * fraction, 1);
  std::vector<CaseRun> runs;
  for (const std::string& c : lichiang_cases()) {
    runs.push_back(walk_case(p, budget, world, storage, w.paths.at(kind), c, w.name + ", " + storage.label + ", " + share + " %, " + kind + ", " + c));
    add_case_row(out, w, storage.label, share, kind, runs.back(), budget);
  }
  const CaseRun &one_step = runs[2], &hybrid = runs[3];
  const bool beats = hybrid.stalls <= one_step.stalls && hybrid.hit_ratio() >= one_step.hit_ratio() &&
                     (hybrid.stalls < one_step.stalls || hybrid.hit_ratio() > one_step.hit_ratio());
  ++out.compared;
  out.beaten += beats;
  out.target_rows += "| " + w.name + " | " + storage.label + " | " + share + " | " + kind + " | " + std::to_string(one_step.stalls) +
                     " → " + std::to_string(hybrid.stalls) + " | " + fixed(100 * one_step.hit_ratio(), 2) + " → " +
                     fixed(100 * hybrid.hit_ratio(), 2) + " | " + (beats ? "yes" : "**no**") + " |\n";
}

// The seed's future work: case 4 with t_p on the frame's thread, over cache shares × t_p.
void walk_tp_grid(const LiChiangBenchParams& p, const BenchWorld& w, const World& world, const Storage& storage, Results& out) {
  const std::string& kind = p.path_kinds.front();
  for (const double fraction : p.plot_fractions) {
    const uint64_t budget = budget_of(w, world, storage, fraction);
    const std::string share = fixed(100 * fraction, 1);
    for (const double tp : p.plot_tp_ms) {
      const std::string name = "lichiang:tp_ms=" + fixed(tp, tp == std::floor(tp) ? 0 : 2);
      const CaseRun r = walk_case(p, budget, world, storage, w.paths.at(kind), name, w.name + ", " + storage.label + ", " + share + " %, t_p " + fixed(tp, 1) + " ms");
      out.tp.push_back({w.name, storage.label, share, kind, fixed(tp, 1), fixed(r.mean_ms, 1), fixed(r.sd_ms, 1),
                        fixed(r.frames ? r.prefetch_ms / double(r.frames) : 0.0, 2), fixed(100 * r.hit_ratio(), 2),
                        std::to_string(r.stalls), fixed(100.0 * r.stall_share(), 2),
                        fixed(double(r.peak) / kMiB, 2) + " / " + fixed(double(budget) / kMiB, 2)});
      out.over_budget += r.peak > budget;
      const std::string series = share + " % cache";
      out.tp_stalls[share].name = out.tp_hits[share].name = out.tp_frame[share].name = series;
      out.tp_stalls[share].points.push_back({tp, 100.0 * r.stall_share()});
      out.tp_hits[share].points.push_back({tp, 100.0 * r.hit_ratio()});
      out.tp_frame[share].points.push_back({tp, r.mean_ms});
    }
  }
}

const std::vector<std::string> kTpHeader = {"world", "storage", "cache % of world", "path", "t_p ms allowed", "frame ms mean", "sd",
                                            "t_p ms used a frame", "hit ratio %", "stall frames", "stall %", "peak / budget MiB"};

void write_plot(const fs::path& file, const std::string& title, const std::string& y_label,
                const std::map<std::string, PlotSeries>& series, double y_max) {
  LinePlot plot;
  plot.title = title;
  plot.x_label = "allowable prefetching time t_p, ms a frame";
  plot.y_label = y_label;
  plot.y_min = 0.0;
  plot.y_max = y_max;
  std::vector<std::pair<double, PlotSeries>> ordered;  // by cache share, not by its text
  for (const auto& [share, s] : series) ordered.emplace_back(std::stod(share), s);
  std::sort(ordered.begin(), ordered.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [share, s] : ordered) plot.series.push_back(s);
  write_file_atomically(file.string(), render_svg(plot));
}

std::string report(const LiChiangBenchParams& p, const std::vector<BenchWorld>& worlds, const Results& r, double minutes) {
  std::string md = "# Li & Chiang: the four cases (seed 003, \"Experimental Results\")\n\n";
  md += "Generated by `" + p.command_line + "` on " + bench::utc_now() + " in " + fixed(minutes, 1) +
        " min; machine: " + bench::machine_info().dump() + ". Every figure comes from this one run.\n\n";
  md += "Worlds: generated cities (houses and towers, landmark fraction " + fixed(p.landmark_fraction, 2) + ", seed " +
        std::to_string(p.city_seed) + "); the seed's two worlds had 128 and 370 objects. Visible sets: the conservative "
        "engine on a " + fixed(p.cell_size, 0) + " m grid, for the cells within " + fixed(p.along_margin, 0) +
        " m of the paths. Paths: " + std::to_string(p.frames) + " frames of each kind, seed " + std::to_string(p.path_seed) +
        " (the seed's were 1,068 and 1,780 steps from a path planner). Images " + std::to_string(p.width) + "×" +
        std::to_string(p.height) + " on llvmpipe; the renderer's buffer cache is held to " + fixed(p.gpu_mib, 1) +
        " MiB so the store is what caches. The budget of every case is the strategy's fixed parts (directory, room for two "
        "loads, the stored sets, the sets of the cells in use) plus a cache share, a fraction of the world's decoded geometry; "
        "each case walks on its own, with a fresh strategy and renderer. Cases 3 and 4 prefetch on a loader thread beside the "
        "frames (t_p is what the frame leaves of the machine).\n\n";
  md += "| world | objects | triangles | geometry MiB | cells with sets | pvs s | fixed parts MiB |\n|---|---|---|---|---|---|---|\n";
  for (const BenchWorld& w : worlds)
    md += "| " + w.name + " | " + std::to_string(w.objects) + " | " + std::to_string(w.triangles) + " | " +
          fixed(double(w.geometry_bytes) / kMiB, 1) + " | " + std::to_string(w.cells) + " | " + fixed(w.pvs_seconds, 1) + " | " +
          fixed(double(w.fixed_bytes) / kMiB, 2) + " |\n";
  md += "\nThe seed (its second world, 370 objects, 1,780 steps; a Pentium II, a DBMS over JDBC): frame time 305.6 / 97.2 / "
        "97.7 / 103.8 ms (sd 133.6 / 52.6 / 51.8 / 46), hit ratio — / 90.9 / 90.8 / 95.2 % for cases 1–4.\n\n";
  md += "## The cases\n\nStorage: the world file read through the OS page cache, then, on each world's " + p.path_kinds.front() +
        " path, ";
  std::string others;
  for (const std::string& kind : p.storages) others += (others.empty() ? "" : "; ") + storage_of(kind, p.read_latency_ms, "", false).label;
  md += (others.empty() ? "nothing else" : others) + ".\n\n" + bench::md_table(kCasesHeader, r.cases, bench::Align::kFigures);
  md += "\nsqlite: the store reads objects from the object database of `cellwalk db`, one prepared query per object, as the "
        "seed's DBMS over JDBC; its budget holds the database's bound besides. I/O ms a miss: the frames' own read time over "
        "their misses (a prefetch reads on the loader thread).\n";
  md += "\nA stall frame read geometry it had to draw. The hit ratio is of the store's requests for geometry to draw "
        "(a prefetched object found resident is a hit; one still loading, a miss).\n";
  md += "\n## Target: hybrid + relevance against LRU + one-step, on stall frames and hit ratio\n\n"
        "| world | storage | cache % | path | stall frames (one-step → hybrid) | hit ratio % | beats on both |\n"
        "|---|---|---|---|---|---|---|\n" + r.target_rows;
  md += "\nBeats on both (neither worse, one better): " + std::to_string(r.beaten) + " of " + std::to_string(r.compared) +
        ". Walks whose strategy peak passed its budget: " + std::to_string(r.over_budget) + " (every walk of this report).\n";
  if (!r.tp.empty()) {
    md += "\n## Cache size against allowable prefetching time (the seed's future work)\n\n"
          "Case 4 (hybrid cache, relevance prefetch) in the seed's frame cycle t_c + t_g + t_p: after each frame the frame's own "
          "thread prefetches for t_p ms (`lichiang:tp_ms=T`; a load once started ends, so t_p used can pass t_p allowed by one "
          "load), on the " + r.tp.front()[0] + " world's " + r.tp.front()[3] + " path, " + r.tp.front()[1] + ".\n\n"
          "![stall frames](lichiang/tp-stalls.svg)\n![hit ratio](lichiang/tp-hits.svg)\n![frame time](lichiang/tp-frame.svg)\n\n" +
          bench::md_table(kTpHeader, r.tp, bench::Align::kFigures);
  }
  return md;
}

}  // namespace

Json run_lichiang_bench(const LiChiangBenchParams& p) {
  if (p.world_objects.empty() || p.path_kinds.empty()) fail("bench lichiang", "give at least one --objects and one --path");
  if (p.cache_fractions.empty()) fail("bench lichiang", "give at least one --cache-fraction");
  for (const std::vector<double>* fractions : {&p.cache_fractions, &p.plot_fractions})
    for (const double f : *fractions)
      if (!(f > 0.0 && f <= 1.0)) fail("bench lichiang", "cache fraction " + fixed(f, 3) + " is not in (0, 1]");
  for (const double tp : p.plot_tp_ms)
    if (!(tp >= 0.0 && tp <= 1e6)) fail("bench lichiang", "--plot-tp " + fixed(tp, 3) + " is not in [0, 1e6] ms");
  for (const std::string& kind : p.storages) storage_of(kind, p.read_latency_ms, "", false);
  for (const std::string& kind : p.path_kinds) parse_session_kind(kind);
  const auto start = bench::Clock::now();
  const bench::WorkDir dir(p.work_dir, "lichiang");
  std::vector<BenchWorld> worlds;
  for (const uint64_t n : p.world_objects) worlds.push_back(prepare(p, dir, n));

  const std::unique_ptr<GlContext> context = GlContext::headless();
  Results r;
  // Written after each world and again at the end, so a run cut short still leaves its report.
  const fs::path out = fs::path(p.out_dir), sub = out / "lichiang";
  auto write_outputs = [&] {
    fs::create_directories(sub);
    bench::write_csv(sub / "cases.csv", kCasesHeader, r.cases);
    if (!r.tp.empty()) {
      bench::write_csv(sub / "tp.csv", kTpHeader, r.tp);
      write_plot(sub / "tp-stalls.svg", "Stall frames against prefetch time, by cache size", "stall frames, %", r.tp_stalls, 100.0);
      write_plot(sub / "tp-hits.svg", "Hit ratio against prefetch time, by cache size", "hit ratio, %", r.tp_hits, 100.0);
      write_plot(sub / "tp-frame.svg", "Frame time against prefetch time, by cache size", "frame time, ms (mean)", r.tp_frame, 0.0);
    }
    write_file_atomically((out / "lichiang.md").string(), report(p, worlds, r, bench::seconds_since(start) / 60.0));
  };
  for (const BenchWorld& w : worlds) {
    const Storage cached = storage_of("", p.read_latency_ms, w.file, false);
    const World world(w.file);
    for (const double fraction : p.cache_fractions)
      for (const std::string& kind : p.path_kinds) walk_cases(p, w, world, cached, fraction, kind, r);
    for (const std::string& kind : p.storages) {
      const Storage storage = storage_of(kind, p.read_latency_ms, w.file, true);
      const World on(w.file, storage.options);
      for (const double fraction : p.cache_fractions) walk_cases(p, w, on, storage, fraction, p.path_kinds.front(), r);
    }
    write_outputs();
  }
  // On the slow disk where there is one: there a miss costs what it cost the seed.
  if (!p.plot_fractions.empty() && !p.plot_tp_ms.empty()) {
    const BenchWorld& largest = *std::max_element(worlds.begin(), worlds.end(), [](const BenchWorld& a, const BenchWorld& b) {
      return a.objects < b.objects;
    });
    const bool slow = std::find(p.storages.begin(), p.storages.end(), "slow") != p.storages.end();
    const Storage storage = storage_of(slow ? "slow" : "", p.read_latency_ms, largest.file, false);
    const World world(largest.file, storage.options);
    walk_tp_grid(p, largest, world, storage, r);
    write_outputs();
  }
  Json summary = r.summary;
  summary["beaten"] = r.beaten;
  summary["compared"] = r.compared;
  summary["over_budget"] = r.over_budget;
  summary["tp_walks"] = r.tp.size();
  return summary;
}

}  // namespace cellwalk
