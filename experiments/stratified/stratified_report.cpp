// `cellwalk bench stratified` (issue 17): the stratified thesis's §6 measured on its random city;
// stratified_report.hpp says what is measured and why.
#include "experiments/stratified/stratified_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/metrics/fidelity.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/scene/path_generator.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/sizing.hpp"
#include "cellwalk/systems/stratified/stored_stratified.hpp"
#include "cellwalk/systems/stratified/stratified_strategy.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"
#include "experiments/common/bench_world.hpp"
#include "experiments/common/svg_plot.hpp"
#include "precompute/pvs_builder.hpp"

namespace cellwalk {
namespace {

namespace fs = std::filesystem;
using bench::fixed;
using bench::Table;
using Json = nlohmann::ordered_json;
using namespace stratified;

constexpr double kMiB = 1048576.0;
double deg(double radians) { return radians * 180.0 / std::numbers::pi; }
double rad(double degrees) { return degrees * std::numbers::pi / 180.0; }

// One α's preprocessing: its world file and what making it cost.
struct Config {
  double alpha_deg = 0;
  std::string file;
  float v = 0;
  uint64_t cells = 0, baked = 0;
  double cells_s = 0, bake_s = 0;
  StratifiedSizes sizes;
};

Config preprocess(const StratifiedBenchParams& p, const World& world, const CameraPath& path, double alpha_deg,
                  const std::string& file) {
  Config c;
  c.alpha_deg = alpha_deg;
  c.file = file;
  const Vec3 size = world.info().bounds.size();
  c.v = float(eq22_viewcell_side(rad(alpha_deg), p.box, std::max(size.x, size.z)));
  const bench::Clock::time_point start = bench::Clock::now();
  std::vector<Aabb> bounds(world.object_count());
  for (ObjectId id = 0; id < world.object_count(); ++id) bounds[id] = world.object(id).bounds;
  Viewcells cells = build_viewcells(default_cell_region(world.info().bounds, world.info().nav, true), c.v, float(p.box), bounds);
  c.cells_s = bench::seconds_since(start);
  cells.partition = visibility::cells_along(*cells.partition, path, p.along_margin);
  FarFieldBaker baker(world, p.resolution);
  Progress progress("bench stratified: bake α = " + fixed(alpha_deg, 1) + "°", 0);
  c.sizes = write_world_with_stratified(
      world, file, cells, {float(rad(alpha_deg)), c.v, float(p.box), "eq22", p.resolution},
      [&](CellId id) { return baker.bake(cells.partition->cell(id).box.center(), float(p.box), cells.near.near(id)); },
      [&](uint64_t done, uint64_t) { progress.update(done); });
  progress.finish();
  c.cells = c.sizes.cells;
  c.baked = c.sizes.baked_cells;
  c.bake_s = c.sizes.bake_seconds;
  return c;
}

// One walker: a strategy on its world with its own renderer (far-face ids are per world).
struct Walker {
  std::string label;
  std::unique_ptr<World> world;
  std::unique_ptr<Strategy> strategy;
  std::unique_ptr<Renderer> renderer;
  StratifiedStrategy* stratified = nullptr;  // when it is one
  double alpha = 0;                          // radians, for stratified walkers
  bool images = false;                       // writes its images of the compared frames
  std::vector<FrameStats> frames;
  std::vector<double> angles;                // far angle per frame (stratified)
  std::vector<bool> crossings;
  std::vector<FidelityFrame> fidelity;
};

RenderSettings render_settings(const StratifiedBenchParams& p) {
  RenderSettings s;
  s.width = p.width;
  s.height = p.height;
  s.backdrop = true;
  return s;
}

Walker make_walker(const std::string& label, const std::string& file, const std::string& strategy,
                   const StratifiedBenchParams& p, double alpha) {
  Walker w;
  w.label = label;
  w.world = std::make_unique<World>(file);
  w.strategy = make_strategy(strategy, *w.world, StrategyOptions{});
  w.renderer = std::make_unique<Renderer>(render_settings(p));
  w.stratified = dynamic_cast<StratifiedStrategy*>(w.strategy.get());
  w.alpha = alpha;
  return w;
}

// Walks every walker along the path, frame by frame in rotating order, and every k-th frame
// compares each with one ground-truth rendering.
void walk_interleaved(std::vector<Walker>& walkers, Walker& truth, const CameraPath& path, const Camera& lens,
                      const StratifiedBenchParams& p, const fs::path& images, const std::string& prefix) {
  Camera camera = lens;
  Progress progress("bench stratified: walk", path.frames.size());
  int written = 0;
  for (size_t i = 0; i < path.frames.size(); ++i) {
    apply(path.frames[i], camera);
    const bool compare = i % size_t(p.fidelity_every) == 0;
    Image truth_color;
    IdImage truth_ids;
    if (compare) {
      render_frame(*truth.strategy, *truth.renderer, camera, path.frames[i].time);
      truth_color = truth.renderer->read_color();
      truth_ids = truth.renderer->read_ids();
    }
    const bool write = compare && written < p.images && i > 0;
    if (write) write_png(truth_color, (images / (prefix + "frame" + std::to_string(i) + "-truth.png")).string());
    for (size_t k = 0; k < walkers.size(); ++k) {
      Walker& w = walkers[(i + k) % walkers.size()];
      FrameStats stats = render_frame(*w.strategy, *w.renderer, camera, path.frames[i].time);
      stats.frame = int(i);
      w.frames.push_back(stats);
      w.angles.push_back(w.stratified ? w.stratified->far_angle(camera) : 0.0);
      w.crossings.push_back(w.stratified && w.stratified->crossed());
      if (!compare) continue;
      Image diff;
      const Image color = w.renderer->read_color();
      FidelityFrame f = compare_images(truth_color, truth_ids, color, w.renderer->read_ids(), &diff);
      f.frame = int(i);
      w.fidelity.push_back(std::move(f));
      if (write && w.images) {
        write_png(color, (images / (prefix + "frame" + std::to_string(i) + "-" + w.label + ".png")).string());
        write_png(diff, (images / (prefix + "frame" + std::to_string(i) + "-" + w.label + "-diff.png")).string());
      }
    }
    written += write;
    progress.update(i + 1);
  }
  progress.finish();
}

struct FrameSummary {
  double mean = 0, sd = 0, p95 = 0, max = 0, ideal_mean = 0, max_load = 0;
  uint64_t triangles = 0, crossings = 0, loads = 0;
};

FrameSummary summarize_frames(const Walker& w) {
  FrameSummary s;
  std::vector<double> ms, ideal;
  for (size_t i = 0; i < w.frames.size(); ++i) {
    const FrameStats& f = w.frames[i];
    ms.push_back(f.frame_ms);
    // Fig. 6-3: the frame without its crossing's load (the thesis removed the spikes by hand).
    ideal.push_back(f.frame_ms - (w.crossings[i] && i > 0 ? f.io_ms + f.decode_ms : 0.0));
    s.triangles += f.triangles;
    if (w.crossings[i] && i > 0) {
      ++s.crossings;
      s.max_load = std::max(s.max_load, f.io_ms + f.decode_ms);
    }
    s.loads += f.stall ? 1 : 0;
  }
  s.mean = bench::mean(ms);
  s.sd = std::sqrt(bench::variance(ms));
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  s.p95 = sorted.empty() ? 0 : sorted[size_t(0.95 * double(sorted.size() - 1))];
  s.max = sorted.empty() ? 0 : sorted.back();
  s.ideal_mean = bench::mean(ideal);
  s.triangles = w.frames.empty() ? 0 : s.triangles / w.frames.size();
  return s;
}

Table table61(const std::vector<Config>& configs) {
  Table rows;
  const char* thesis[][3] = {{"33", "50 min", "4M"}, {"5", "14,000 min (projected)", "1155M (projected)"}};
  for (size_t i = 0; i < configs.size(); ++i) {
    const Config& c = configs[i];
    const uint64_t stored = c.sizes.color_bytes + c.sizes.id_bytes + c.sizes.depth_bytes;
    const double per_cell_s = c.baked ? c.bake_s / double(c.baked) : 0.0;
    const double per_cell_bytes = c.baked ? double(stored) / double(c.baked) : 0.0;
    rows.push_back({fixed(c.alpha_deg, 1) + "°", fixed(c.v, 2), std::to_string(c.cells), std::to_string(c.baked),
                    fixed(1e3 * per_cell_s, 0), fixed(per_cell_s * double(c.cells) / 60.0, 1), fixed(c.cells_s, 2),
                    fixed(per_cell_bytes / 1024.0, 1), fixed(per_cell_bytes * double(c.cells) / kMiB, 1),
                    fixed(c.baked ? double(c.sizes.raw_face_bytes) / double(stored) : 0.0, 1),
                    i < 2 ? std::string(thesis[i][0]) + " m; " + thesis[i][1] + "; " + thesis[i][2] : "—"});
  }
  return rows;
}

const std::vector<std::string> kTable61Header = {
    "α", "v (m)", "cells", "baked", "bake ms / cell", "all cells, min (from the rate)", "near lists, s (all cells)",
    "stored KiB / cell", "all cells, MiB", "raw / stored", "thesis: v; preprocessing; storage"};

const std::vector<std::string> kFramesHeader = {"path seed", "strategy", "frame ms mean", "sd", "p95", "max", "speed-up vs brute",
                                                "ideal ms (loads out, Fig. 6-3)", "triangles / frame", "crossings",
                                                "stall frames (loaded a cell)", "largest crossing ms"};

const std::vector<std::string> kFidelityHeader = {
    "path seed", "strategy", "frames compared", "PSNR dB", "differing pixels mean %", "max %", "missed of visible",
    "largest missed, px of truth", "pixel error max px",
    "far angle max (measured)", "α", "frames over α"};

std::string frame_times_svg(const std::vector<Walker>& walkers, const std::string& path_name) {
  LinePlot plot;
  plot.title = "Frame time along " + path_name + " (Figs. 6-1, 6-2)";
  plot.x_label = "frame";
  plot.y_label = "ms";
  for (const Walker& w : walkers) {
    PlotSeries s{w.label, {}};
    for (const FrameStats& f : w.frames) s.points.push_back({double(f.frame), f.frame_ms});
    plot.series.push_back(std::move(s));
  }
  return render_svg(plot);
}

}  // namespace

Json run_stratified_bench(const StratifiedBenchParams& p) {
  if (p.alphas_deg.empty()) fail("bench stratified", "give at least one --alpha");
  if (p.fidelity_every < 1 || p.frames < 1) fail("bench stratified", "--frames and --fidelity-every must be at least 1");
  const bench::Clock::time_point start = bench::Clock::now();
  const bench::WorkDir dir(p.work_dir, "stratified");
  const std::string world_file = dir.file("city.cww");
  bench::WorldBuild build;
  build.progress_label = "bench stratified: build";
  const BuildReport built = bench::make_bench_world(p.city, build, dir.file("city.cwscene"), world_file);
  const World world(world_file);
  std::vector<std::pair<uint64_t, CameraPath>> paths;
  CameraPath every_path;  // the cells along any path are baked
  for (const uint64_t seed : p.path_seeds) {
    PathParams path_params;
    path_params.kind = parse_session_kind(p.path_kind);
    path_params.frames = p.frames;
    path_params.seed = seed;
    paths.emplace_back(seed, generate_path(world.info().nav, path_params));
    every_path.frames.insert(every_path.frames.end(), paths.back().second.frames.begin(), paths.back().second.frames.end());
  }

  std::vector<Config> configs;
  for (const double a : p.alphas_deg)
    configs.push_back(preprocess(p, world, every_path, a, dir.file("city-alpha" + fixed(a, 1) + ".cww")));

  const std::unique_ptr<GlContext> context = GlContext::headless();
  Camera lens;
  lens.fov_y_deg = float(p.fov_deg);
  lens.aspect = float(p.width) / float(p.height);
  const fs::path out = fs::path(p.out_dir), sub = out / "stratified";
  fs::create_directories(sub);
  Table frames_rows, fidelity_rows, per_frame;
  Json summary = {{"world", {{"objects", world.object_count()}, {"triangles", world.triangle_count()}}}, {"paths", Json::object()}};
  for (const auto& [seed, path] : paths) {
    const std::string path_name = p.path_kind + " path, seed " + std::to_string(seed);
    std::vector<Walker> walkers;
    walkers.push_back(make_walker("brute", world_file, "brute", p, 0.0));
    for (const Config& c : configs) {
      walkers.push_back(make_walker("stratified-" + fixed(c.alpha_deg, 1), c.file, "stratified", p, rad(c.alpha_deg)));
      walkers.back().images = true;  // the -noprefetch runs draw the same images
    }
    // The thesis's own run time: every crossing loads in its frame.
    for (const Config& c : configs)
      walkers.push_back(make_walker("stratified-" + fixed(c.alpha_deg, 1) + "-noprefetch", c.file, "stratified:prefetch=0", p,
                                    rad(c.alpha_deg)));
    Walker truth = make_walker("truth", world_file, "ground-truth", p, 0.0);
    walk_interleaved(walkers, truth, path, lens, p, sub, "seed" + std::to_string(seed) + "-");
    const double brute_ms = summarize_frames(walkers.front()).mean;
    for (const Walker& w : walkers) {
      const FrameSummary s = summarize_frames(w);
      frames_rows.push_back({std::to_string(seed), w.label, fixed(s.mean, 2), fixed(s.sd, 2), fixed(s.p95, 2), fixed(s.max, 2),
                             fixed(s.mean > 0 ? brute_ms / s.mean : 0.0, 2) + "×", fixed(s.ideal_mean, 2),
                             std::to_string(s.triangles), std::to_string(s.crossings), std::to_string(s.loads),
                             fixed(s.max_load, 1)});
      const FidelitySummary f = summarize(w.fidelity);
      const double worst = w.angles.empty() ? 0.0 : *std::max_element(w.angles.begin(), w.angles.end());
      const auto over = std::count_if(w.angles.begin(), w.angles.end(), [&](double a) { return w.stratified && a > w.alpha; });
      fidelity_rows.push_back({std::to_string(seed), w.label, std::to_string(f.frames),
                               std::isfinite(f.mean_psnr_db) ? fixed(f.mean_psnr_db, 1) : "inf",
                               fixed(100 * f.mean_differing_fraction, 3), fixed(100 * f.max_differing_fraction, 3),
                               std::to_string(f.missed_objects) + " of " + std::to_string(f.visible_objects),
                               std::to_string(f.largest_missed_pixels), fixed(f.max_pixel_error_px, 1), w.stratified ? fixed(deg(worst), 2) + "°" : "—",
                               w.stratified ? fixed(deg(w.alpha), 1) + "°" : "—", w.stratified ? std::to_string(over) : "—"});
      summary["paths"][std::to_string(seed)][w.label] = {
          {"frame_ms", s.mean}, {"speedup", s.mean > 0 ? brute_ms / s.mean : 0.0}, {"triangles", s.triangles},
          {"crossings", s.crossings}, {"stall_frames", s.loads}, {"max_far_angle_deg", deg(worst)}, {"frames_over_alpha", over},
          {"psnr_db", std::isfinite(f.mean_psnr_db) ? Json(f.mean_psnr_db) : Json(nullptr)},
          {"missed", f.missed_objects}, {"visible", f.visible_objects}};
      for (size_t i = 0; i < w.frames.size(); ++i)
        per_frame.push_back({std::to_string(seed), w.label, std::to_string(w.frames[i].frame), fixed(w.frames[i].frame_ms, 3),
                             std::to_string(w.frames[i].triangles), w.crossings[i] ? "1" : "0",
                             fixed(w.frames[i].io_ms + w.frames[i].decode_ms, 3), fixed(deg(w.angles[i]), 4)});
    }
    write_file_atomically((sub / ("frame-times-seed" + std::to_string(seed) + ".svg")).string(), frame_times_svg(walkers, path_name));
  }
  const Table t61 = table61(configs);
  bench::write_csv(sub / "table61.csv", kTable61Header, t61);
  bench::write_csv(sub / "frames.csv",
                   {"path_seed", "strategy", "frame", "frame_ms", "triangles", "crossing", "load_ms", "far_angle_deg"}, per_frame);

  std::string md = "# Stratified rendering: the thesis's experiments (seed 002 §6)\n\n";
  md += "Generated by `" + p.command_line + "` on " + bench::utc_now() + " in " + fixed(bench::seconds_since(start) / 60.0, 1) +
        " min; machine: " + bench::machine_info().dump() + ". Every figure comes from this one run; the walks are "
        "interleaved frame by frame, each strategy with its own renderer.\n\n";
  const Vec3 size = world.info().bounds.size();
  md += "City: Appendix A's random city, " + fixed(size.x, 0) + " × " + fixed(size.z, 0) + " × " + fixed(size.y, 0) +
        " m, " + std::to_string(world.object_count()) + " objects, " + std::to_string(world.triangle_count()) +
        " triangles (the thesis: 1 km × 1 km × 67 m, ~83,000 polygons); built in " + fixed(built.seconds, 1) +
        " s. b = " + fixed(p.box, 0) + " m, faces " + std::to_string(p.resolution) + "², " + std::to_string(p.width) + "×" +
        std::to_string(p.height) + " images at " + fixed(p.fov_deg, 0) + "° field, llvmpipe; " +
        std::to_string(p.path_seeds.size()) + " " + p.path_kind + " paths of " + std::to_string(p.frames) +
        " frames (seeds as in the tables: a path along the city's edge looks out of it and sees little, one through it "
        "sees much). Only the cells within " + fixed(p.along_margin, 0) +
        " m of the paths are baked; preprocessing and storage for every cell are projected from the measured rate.\n\n";
  md += "## Table 6.1\n\n" + bench::md_table(kTable61Header, t61, bench::Align::kFigures);
  md += "\n## Frame time (Figs. 6-1 to 6-3)\n\n" + bench::md_table(kFramesHeader, frames_rows, bench::Align::kFigures);
  for (const auto& [seed, path] : paths)
    md += "\n![frame times, seed " + std::to_string(seed) + "](stratified/frame-times-seed" + std::to_string(seed) + ".svg)\n";
  md += "\n`-noprefetch` is the thesis's run time: a crossing loads the "
        "new cell's near list and far faces in its frame (a stall frame); 'ideal' takes those loads out (Fig. 6-3). "
        "Without the suffix, a thread loads the cells the viewer's velocity reaches within 1.5 s, so a crossing finds its "
        "cell loaded; a stall frame is one that had to load its cell or wait for the prefetcher.\n";
  md += "\n## Fidelity against ground truth, and the far field's angular error\n\n" +
        bench::md_table(kFidelityHeader, fidelity_rows, bench::Align::kFigures);
  md += "\nEvery " + std::to_string(p.fidelity_every) +
        "th frame is compared. The far angle is measured on every frame: the largest angle, over the far texels in view, "
        "between where the far point is (from the stored depth) and where its face shows it, seen from the eye. "
        "Difference images (128 + test − truth, the thesis's Figs. 6-4 to 6-7) are in `stratified/frame*-diff.png`.\n";
  write_file_atomically((out / "stratified.md").string(), md);
  return summary;
}

}  // namespace cellwalk
