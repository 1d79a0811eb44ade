// `cellwalk bench visual`: HDoV thesis §5.8 (digest §5.5) reproduced on a generated city.
#include "metrics/visual_bench.hpp"

#include <algorithm>
#include <filesystem>

#include "cellwalk/atomic_file.hpp"
#include "cellwalk/error.hpp"
#include "cellwalk/generators.hpp"
#include "cellwalk/hdov_tree.hpp"
#include "cellwalk/path.hpp"
#include "cellwalk/random.hpp"
#include "cellwalk/review.hpp"
#include "cellwalk/scene_file.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"
#include "metrics/bench_support.hpp"
#include "metrics/svg_plot.hpp"
#include "visibility/pvs_builder.hpp"

namespace cellwalk {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;
using bench::fixed;
using bench::md_table;
using bench::mean;
using bench::Table;
using bench::variance;
using bench::write_csv;

// The city, its world (LOD chains), DoVs per grid cell from the dov engine, the HDoV-tree.
struct Setup {
  std::string world_file, tree_file;
  std::unique_ptr<World> world;
  std::unique_ptr<HdovTree> tree;
  uint64_t visible_nodes = 0;
  double dov_seconds = 0, tree_seconds = 0;
};

Setup make_setup(const VisualBenchParams& p, const fs::path& dir) {
  Setup s;
  const std::string scene = (dir / "city.cwscene").string();
  const std::string raw = (dir / "city-raw.cww").string();
  s.world_file = (dir / "city.cww").string();
  {
    SceneWriter writer(scene);
    CityParams city;
    city.objects = p.objects;
    city.seed = p.seed;
    writer.finish(generate_city(city, writer));
  }
  BuildParams build;
  build.threads = p.threads;
  {
    Progress progress("build world", p.objects);
    // REVIEW, the baseline of Exp. 3, queries the world's own R-tree (its default fan-out).
    build_world(scene, raw, build, [&](uint64_t done, uint64_t) { progress.update(done); },
                [&](WorldWriter& writer, std::span<const Aabb> bounds) {
                  write_rtree_section(build_rtree(bounds, RTreeParams{.max_entries = 32}, writer.page_size()), writer);
                });
    progress.finish();
  }
  fs::remove(scene);
  {
    const World world(raw);
    CellRegion region = default_cell_region(world.info().bounds, world.info().nav, true);
    const float side = std::max(region.bounds.size().x, region.bounds.size().z) / float(p.cells_per_side);
    const auto cells = make_grid_partition(region, side);
    EngineOptions options;
    options.dov_resolution = p.dov_resolution;
    const auto engine = make_engine("dov", world, options);
    visibility::PvsRun run;
    run.engine = engine->name();
    run.settings = "visual bench, dov resolution " + std::to_string(p.dov_resolution);
    run.threads = p.threads;
    Stopwatch watch;
    std::unique_ptr<Progress> progress;
    const auto sets = visibility::compute_cell_sets(world, *engine, *cells, run, (dir / "dov.checkpoint").string(),
                                                    [&](uint64_t done, uint64_t total) {
                                                      if (!progress) progress = std::make_unique<Progress>("DoV per cell", total);
                                                      progress->update(done);
                                                    });
    if (progress) progress->finish();
    s.dov_seconds = watch.ms() / 1000;
    visibility::write_world_with_pvs(world, s.world_file, *cells, sets, run);
  }
  fs::remove(raw);
  s.world = std::make_unique<World>(s.world_file);
  s.tree_file = default_hdov_path(s.world_file);
  HdovBuildParams hp;
  hp.max_entries = p.fanout;
  Stopwatch watch;
  Progress progress("HDoV-tree", 0);
  s.visible_nodes = build_visual_tree(*s.world, s.tree_file, hp, [&](uint64_t d, uint64_t) { progress.update(d); }).visible_nodes();
  progress.finish();
  s.tree_seconds = watch.ms() / 1000;
  s.tree = std::make_unique<HdovTree>(*s.world, s.tree_file);
  return s;
}

// Non-solid cells with something visible, and the two query streams of Exp. 1: a chain of
// adjacent cells (a walk over face neighbours) and random cells.
std::vector<CellId> usable_cells(const HdovTree& tree) {
  std::vector<CellId> cells;
  for (CellId c = 0; c < tree.cell_count(); ++c)
    if (!tree.cells().cell(c).solid && tree.iv_directory()[c].second > 0) cells.push_back(c);
  return cells;
}
std::vector<CellId> continuous_queries(const HdovTree& tree, const std::vector<CellId>& usable, int n, Random& rng) {
  std::vector<CellId> out{usable.front()};
  while (int(out.size()) < n) {
    std::vector<CellId> next;
    for (CellId c : tree.cells().face_neighbours(out.back()))
      if (std::find(usable.begin(), usable.end(), c) != usable.end()) next.push_back(c);
    out.push_back(next.empty() ? usable[rng.integer(0, int(usable.size()) - 1)] : next[rng.integer(0, int(next.size()) - 1)]);
  }
  return out;
}
std::vector<CellId> random_queries(const std::vector<CellId>& usable, int n, Random& rng) {
  std::vector<CellId> out;
  for (int i = 0; i < n; ++i) out.push_back(usable[rng.integer(0, int(usable.size()) - 1)]);
  return out;
}

struct Walk {
  std::vector<double> frame_ms;
  uint64_t peak = 0, triangles = 0, queries = 0, ios = 0;
};

// Replays `path` headless: frame time = the strategy's select and mesh calls (query, I/O,
// decode) + triangles / the modelled render rate; the same for every strategy.
Walk replay(Strategy& s, const CameraPath& path, const VisualBenchParams& p) {
  Walk w;
  Camera camera;
  camera.fov_y_deg = 45;
  camera.aspect = 1;
  camera.near_plane = 0.5f;
  camera.far_plane = 400.0f;
  for (const PathFrame& f : path.frames) {
    apply(f, camera);
    std::vector<DrawItem> items;
    FrameStats stats;
    Stopwatch watch;
    s.select(camera, items, stats);
    uint64_t triangles = 0;
    for (const DrawItem& item : items)
      if (const Mesh* m = s.mesh(item, stats)) triangles += m->triangle_count();
    w.triangles += triangles;
    w.frame_ms.push_back(watch.ms() + double(triangles) / (p.render_mtri_per_s * 1e3));
  }
  w.peak = s.peak_resident_bytes();
  return w;
}

}  // namespace

Json run_visual_bench(const VisualBenchParams& p) {
  Stopwatch total;
  const fs::path out = fs::path(p.out_dir) / "visual";
  fs::create_directories(out);
  const bench::WorkDir work(p.work_dir, "visual");
  const fs::path& dir = work.path();
  Setup s = make_setup(p, dir);
  const HdovTree& tree = *s.tree;
  const std::vector<CellId> usable = usable_cells(tree);
  if (usable.empty()) fail("bench visual", "no cell sees anything: the city is too small for the cell grid");
  Json summary;
  std::string md = "# VISUAL (HDoV thesis chapter 5) reproduced\n\nWritten by `" + p.command_line + "`. Design: [../visual.md](../visual.md).\n\n";
  md += "Setup: a generated city of " + std::to_string(p.objects) + " objects (" + std::to_string(s.world->triangle_count()) +
        " triangles at level 0), " + std::to_string(tree.cell_count()) + " grid view cells (" + std::to_string(usable.size()) +
        " see something), DoV by the `dov` engine at **" + std::to_string(p.dov_resolution) + "² per cube face** (the thesis: 256²; lowered to keep the bench under 10 minutes on 2 cores; " +
        fixed(s.dov_seconds, 1) + " s for all cells), HDoV-tree M = " + std::to_string(tree.max_entries()) + ", " +
        std::to_string(tree.node_count()) + " nodes, height " + std::to_string(tree.height()) + " (built in " + fixed(s.tree_seconds, 1) + " s).\n\n";

  // ---- Table 5.2 ----
  Table storage_rows;
  const char* thesis[] = {"4 GB", "267 MB", "152.8 MB"};
  int i = 0;
  for (VPageScheme sc : {VPageScheme::kHorizontal, VPageScheme::kVertical, VPageScheme::kIndexedVertical}) {
    const SchemeStorage m = tree.storage(sc);
    const SchemeStorage f = formula_storage(sc, tree.node_count(), tree.cell_count(), s.visible_nodes, tree.vpage_size());
    storage_rows.push_back({vpage_scheme_name(sc), std::to_string(m.total()), std::to_string(f.total()),
                            fixed(double(tree.storage(VPageScheme::kHorizontal).total()) / double(m.total()), 2), thesis[i++]});
    summary["storage"][vpage_scheme_name(sc)] = m.total();
  }
  storage_rows.push_back({"naive lists", std::to_string(tree.naive_bytes()), "", "", ""});
  write_csv(out / "storage.csv", {"scheme", "measured_bytes", "formula_bytes", "horizontal_over_this", "thesis"}, storage_rows);
  md += "## Table 5.2: storage of the V-data\n\nBytes of V-pages + V-page index (eqs. 5.7–5.9; indexed-vertical adds its 8-byte-per-cell directory):\n\n";
  md += md_table({"scheme", "measured", "formula", "horizontal / this", "thesis"}, storage_rows);
  md += "\n[CSV](visual/storage.csv)\n\n";

  // ---- Exp. 1: caching ----
  Random rng(p.seed);
  const std::vector<CellId> cont = continuous_queries(tree, usable, p.queries, rng);
  const std::vector<CellId> rand = random_queries(usable, p.queries, rng);
  Table cache_rows;
  const std::vector<HdovCacheOptions::Policy> policies = {HdovCacheOptions::Policy::kLru, HdovCacheOptions::Policy::kDov,
                                                          HdovCacheOptions::Policy::kDovTime};
  Progress cache_progress("Exp. 1 caches", 2 * 3 * policies.size() * p.cache_pages.size());
  uint64_t step = 0;
  for (const auto& [stream, queries] : {std::pair{"continuous", &cont}, std::pair{"random", &rand}})
    for (double eta : {0.00001, 0.0001, 0.0005}) {
      LinePlot plot{.title = std::string("Hit rate, ") + stream + " queries, eta = " + fixed(eta, 5), .x_label = "cache size (node pages)",
                    .y_label = "hit rate %", .log_x = true, .y_min = 0, .y_max = 100};
      for (auto policy : policies) {
        PlotSeries series{hdov_cache_policy_name(policy), {}};
        for (double pages : p.cache_pages) {
          HdovSearcher searcher(tree, VPageScheme::kIndexedVertical, {.policy = policy, .pages = uint64_t(pages)});
          HdovCounters io;
          std::vector<HdovPick> picks;
          for (CellId c : *queries) {
            searcher.flip(c, io);
            picks.clear();
            searcher.search({.eta = eta}, picks, io);
          }
          const BufferCounters bc = searcher.cache_counters();
          const double rate = 100.0 * double(bc.hits) / double(std::max<uint64_t>(1, bc.hits + bc.misses));
          series.points.emplace_back(pages, rate);
          cache_rows.push_back({stream, fixed(eta, 5), hdov_cache_policy_name(policy), fixed(pages, 0), fixed(rate, 2),
                                fixed(double(io.node_visits) / double(queries->size()), 1)});
          cache_progress.update(++step);
        }
        plot.series.push_back(series);
      }
      write_file_atomically((out / ("hit_rate_" + std::string(stream) + "_" + fixed(eta, 5) + ".svg")).string(), render_svg(plot));
    }
  cache_progress.finish();
  write_csv(out / "cache.csv", {"queries", "eta", "policy", "cache_pages", "hit_rate_pct", "node_visits_per_query"}, cache_rows);
  md += "## Exp. 1 (Figs. 5.15–5.20): node cache hit rate vs cache size\n\n" + std::to_string(p.queries) +
        " queries per run (indexed-vertical), only tree-node pages counted; the tree has " + std::to_string(tree.node_count()) + " node pages.\n\n";
  md += md_table({"queries", "η", "policy", "cache pages", "hit rate %", "node visits / query"}, cache_rows);
  md += "\n";
  for (const char* stream : {"continuous", "random"})
    for (double eta : {0.00001, 0.0001, 0.0005})
      md += "![](visual/hit_rate_" + std::string(stream) + "_" + fixed(eta, 5) + ".svg)\n";
  md += "\n[CSV](visual/cache.csv)\n\n";

  // ---- Exp. 2: search time and I/O vs η ----
  Table search_rows;
  LinePlot time_plot{.title = "Search time vs eta (random queries)", .x_label = "eta", .y_label = "ms per query"};
  LinePlot io_plot{.title = "Light-weight page I/O vs eta", .x_label = "eta", .y_label = "pages per query"};
  auto record = [&](const std::string& label, double eta, double ms, const HdovCounters& io, uint64_t picks, uint64_t triangles,
                    PlotSeries& ts, PlotSeries& is) {
    const double n = double(rand.size());
    search_rows.push_back({label, fixed(eta, 4), fixed(ms / n, 4), fixed(double(io.light_ios()) / n, 1), fixed(double(io.vpage_reads) / n, 1),
                           fixed(double(io.vpage_seeks) / n, 1), fixed(double(io.index_reads) / n, 2), fixed(double(picks) / n, 1),
                           fixed(double(triangles) / n, 0)});
    ts.points.emplace_back(eta, ms / n);
    is.points.emplace_back(eta, double(io.light_ios()) / n);
  };
  for (VPageScheme sc : {VPageScheme::kHorizontal, VPageScheme::kVertical, VPageScheme::kIndexedVertical}) {
    PlotSeries ts{vpage_scheme_name(sc), {}}, is{vpage_scheme_name(sc), {}};
    for (double eta : p.etas) {
      HdovSearcher searcher(tree, sc, {.policy = HdovCacheOptions::Policy::kNone});
      HdovCounters io;
      std::vector<HdovPick> picks;
      uint64_t count = 0, triangles = 0;
      Stopwatch watch;
      for (CellId c : rand) {
        searcher.flip(c, io);
        picks.clear();
        searcher.search({.eta = eta}, picks, io);
        count += picks.size();
        for (const HdovPick& pk : picks) triangles += pk.triangles;
      }
      record(vpage_scheme_name(sc), eta, watch.ms(), io, count, triangles, ts, is);
    }
    time_plot.series.push_back(ts);
    io_plot.series.push_back(is);
  }
  {
    PlotSeries ts{"naive", {}}, is{"naive", {}};
    HdovCounters io;
    std::vector<HdovPick> picks;
    uint64_t count = 0, triangles = 0;
    Stopwatch watch;
    for (CellId c : rand) {
      picks.clear();
      naive_search(tree, c, 0.5, picks, io);
      count += picks.size();
      for (const HdovPick& pk : picks) triangles += pk.triangles;
    }
    const double ms = watch.ms();
    for (double eta : {p.etas.front(), p.etas.back()}) record("naive", eta, ms, io, count, triangles, ts, is);
    search_rows.pop_back();
    time_plot.series.push_back(ts);
    io_plot.series.push_back(is);
  }
  write_file_atomically((out / "search_time.svg").string(), render_svg(time_plot));
  write_file_atomically((out / "search_io.svg").string(), render_svg(io_plot));
  const std::vector<std::string> search_header = {"method", "η", "ms / query", "light I/O / query", "V-pages", "V-page seeks",
                                                  "index pages (flip)", "picks", "triangles"};
  write_csv(out / "search.csv", search_header, search_rows);
  md += "## Exp. 2 (Figs. 5.21–5.22): search time and page I/O vs η\n\n" + std::to_string(rand.size()) +
        " random cells, no node cache (every node visit is a page read), times include the flip; light I/O = node pages + V-pages + index pages (+ list pages for naive):\n\n";
  md += md_table(search_header, search_rows);
  md += "\n![](visual/search_time.svg)\n![](visual/search_io.svg)\n\n[CSV](visual/search.csv)\n\n";

  // ---- Exp. 3: walkthrough vs REVIEW ----
  PathParams pp;
  pp.frames = p.frames;
  pp.seed = p.seed;
  pp.fps = 10;
  const CameraPath path = generate_path(s.world->info().nav, pp);
  Table walk_rows;
  std::vector<std::pair<std::string, Walk>> walks;
  Progress walk_progress("Exp. 3 walks", p.walk_etas.size() + 1);
  StrategyOptions options;
  for (double eta : p.walk_etas) {
    VisualConfig config;
    config.eta = eta;
    config.tree_file = s.tree_file;
    VisualStrategy v(*s.world, config, options);
    Walk w = replay(v, path, p);
    w.queries = v.queries().size();
    for (const VisualQuery& q : v.queries()) w.ios += q.io.light_ios();
    walks.emplace_back("VISUAL η=" + fixed(eta, 4), std::move(w));
    walk_progress.update(walks.size());
  }
  {
    ReviewConfig rc;
    rc.depth = 400;  // the thesis's 400 m query boxes
    ReviewStrategy r(*s.world, rc, options);
    Walk w = replay(r, path, p);
    w.queries = r.queries().size();
    for (const ReviewQuery& q : r.queries()) w.ios += q.disk_ios();
    walks.emplace_back("REVIEW (400 m)", std::move(w));
    walk_progress.update(walks.size());
  }
  walk_progress.finish();
  const double review_ms = mean(walks.back().second.frame_ms);
  LinePlot frame_plot{.title = "Frame time, one session", .x_label = "frame", .y_label = "ms"};
  for (const auto& [label, w] : walks) {
    walk_rows.push_back({label, fixed(mean(w.frame_ms), 2), fixed(variance(w.frame_ms), 2), fixed(review_ms / mean(w.frame_ms), 2),
                         fixed(double(w.triangles) / double(w.frame_ms.size()), 0), std::to_string(w.queries),
                         fixed(double(w.peak) / 1048576.0, 2)});
    PlotSeries series{label, {}};
    for (size_t f = 0; f < w.frame_ms.size(); ++f) series.points.emplace_back(double(f), w.frame_ms[f]);
    frame_plot.series.push_back(series);
    summary["walk"][label] = {{"mean_ms", mean(w.frame_ms)}, {"variance", variance(w.frame_ms)}, {"peak_bytes", w.peak}};
  }
  write_file_atomically((out / "frames.svg").string(), render_svg(frame_plot));
  const std::vector<std::string> walk_header = {"system", "mean frame ms", "variance ms²", "REVIEW / this", "triangles / frame", "queries", "peak MiB"};
  write_csv(out / "walk.csv", walk_header, walk_rows);
  md += "## Exp. 3 (Table 5.3, Figs. 5.24–5.27): walkthrough vs REVIEW\n\nOne normal session of " + std::to_string(p.frames) +
        " frames, replayed headless by every system: frame time = measured select + mesh fetches + triangles / " +
        fixed(p.render_mtri_per_s, 1) + " M triangles/s (modelled render). No budget. Thesis (Table 5.3): VISUAL 15.92 ms (η = 0) … 12.78 ms (η = 0.001) vs REVIEW (400 m) 57.84 ms; peak memory 28 MB vs 62 MB.\n\n";
  md += md_table(walk_header, walk_rows);
  md += "\n![](visual/frames.svg)\n\n[CSV](visual/walk.csv)\n\n";
  md += "## Not measured here\n\n- Fig. 5.23 (search vs world size) and per-η fidelity through `compare` are not run by this bench yet (see docs/visual.md).\n\n";
  md += "## Reading\n\nSee docs/visual.md, section \"Results\", for the comparison with the thesis.\n";
  write_file_atomically((fs::path(p.out_dir) / "visual.md").string(), md);
  summary["seconds"] = total.ms() / 1000;
  return summary;
}

}  // namespace cellwalk
