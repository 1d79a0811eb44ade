// `cellwalk bench stratified` (issue 17): the stratified thesis's §6 measured on its random city;
// stratified_report.hpp says what is measured and why.
#include "experiments/stratified/stratified_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>
#include <optional>
#include <set>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/metrics/fidelity.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/runtime/walk.hpp"
#include "cellwalk/scene/path_generator.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/bake_pool.hpp"
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
  if (cells.partition->cell_count() > p.bake_all_up_to) cells.partition = visibility::cells_along(*cells.partition, path, p.along_margin);
  const bench::Clock::time_point bake_start = bench::Clock::now();
  std::vector<BakeJob> jobs;
  for (CellId id = 0; id < cells.partition->cell_count(); ++id)
    if (cells.partition->cell(id).computed()) jobs.push_back({cells.partition->cell(id).box.center(), float(p.box), cells.near.near(id)});
  const uint64_t jobs_count = jobs.size();
  BakePool pool(world, {.resolution = p.resolution, .max_texels = p.far_level_texels}, p.bake_threads, std::move(jobs));
  Progress progress("bench stratified: bake α = " + fixed(alpha_deg, 1) + "°", 0);
  double bake_s = 0.0;  // until the last record is baked: writing the world is not baking
  uint64_t taken = 0;
  const uint64_t to_take = jobs_count;
  c.sizes = write_world_with_stratified(
      world, file, cells, {float(rad(alpha_deg)), c.v, float(p.box), "eq22", p.resolution, p.far_level_texels},
      [&](CellId) {
        std::vector<uint8_t> record = pool.next();
        if (++taken == to_take) bake_s = bench::seconds_since(bake_start);
        return record;
      },
      [&](uint64_t done, uint64_t) { progress.update(done); });
  progress.finish();
  c.cells = c.sizes.cells;
  c.baked = c.sizes.baked_cells;
  c.bake_s = bake_s;
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
  int every = 1;                             // draws every `every`-th frame and the compared ones
  std::vector<FrameStats> frames;
  std::vector<double> angles;                // far angle per frame (stratified)
  std::vector<bool> crossings;
  std::vector<FidelityFrame> fidelity;
  // With track_change, per frame drawn the mean absolute change of its colour from the frame
  // before (0 for the first): what a crossing's jump, or its cross-fade, shows the viewer.
  bool track_change = false;
  std::vector<double> change;
  Image last_color;
};

// The mean absolute difference of the colour channels of two images of one size.
double mean_change(const Image& a, const Image& b) {
  uint64_t sum = 0;
  for (size_t i = 0; i < a.rgba.size(); i += 4)
    for (size_t ch = 0; ch < 3; ++ch) sum += uint64_t(std::abs(int(a.rgba[i + ch]) - int(b.rgba[i + ch])));
  return a.rgba.empty() ? 0.0 : double(sum) / double(a.rgba.size() / 4 * 3);
}

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
  StrategyOptions options;
  options.viewport_height_px = float(p.height);  // lod's screen-space error
  w.strategy = make_strategy(strategy, *w.world, options);
  w.renderer = std::make_unique<Renderer>(render_settings(p));
  w.stratified = dynamic_cast<StratifiedStrategy*>(w.strategy.get());
  w.alpha = alpha;
  return w;
}

// Walks every walker along the path, frame by frame in rotating order, and every k-th frame
// compares each with one ground-truth rendering.
void walk_interleaved(std::vector<Walker>& walkers, Walker& truth, const CameraPath& path, const Camera& lens,
                      int fidelity_every, int images_to_write, const fs::path& images, const std::string& prefix) {
  Camera camera = lens;
  Progress progress("bench stratified: walk", path.frames.size());
  int written = 0;
  for (size_t i = 0; i < path.frames.size(); ++i) {
    apply(path.frames[i], camera);
    const bool compare = i % size_t(fidelity_every) == 0;
    Image truth_color;
    IdImage truth_ids;
    if (compare) {
      render_frame(*truth.strategy, *truth.renderer, camera, path.frames[i].time);
      truth_color = truth.renderer->read_color();
      truth_ids = truth.renderer->read_ids();
    }
    const bool write = compare && written < images_to_write && i > 0;
    if (write) write_png(truth_color, (images / (prefix + "frame" + std::to_string(i) + "-truth.png")).string());
    for (size_t k = 0; k < walkers.size(); ++k) {
      Walker& w = walkers[(i + k) % walkers.size()];
      if (!compare && i % size_t(w.every) != 0) continue;
      FrameStats stats = render_frame(*w.strategy, *w.renderer, camera, path.frames[i].time);
      stats.frame = int(i);
      w.frames.push_back(stats);
      w.angles.push_back(w.stratified ? w.stratified->far_angle(camera) : 0.0);
      w.crossings.push_back(w.stratified && w.stratified->crossed());
      if (w.track_change) {
        Image color = w.renderer->read_color();
        w.change.push_back(w.last_color.rgba.empty() ? 0.0 : mean_change(color, w.last_color));
        w.last_color = std::move(color);
      }
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

// thesis: the rows are Table 6.1's configurations A and B, with the thesis's figures beside them.
Table table61(const std::vector<Config>& configs, bool thesis) {
  Table rows;
  const char* thesis_figures[][3] = {{"33", "50 min", "4M"}, {"5", "14,000 min (projected)", "1155M (projected)"}};
  for (size_t i = 0; i < configs.size(); ++i) {
    const Config& c = configs[i];
    const uint64_t stored = c.sizes.color_bytes + c.sizes.id_bytes + c.sizes.depth_bytes;
    const double per_cell_s = c.baked ? c.bake_s / double(c.baked) : 0.0;
    const double per_cell_bytes = c.baked ? double(stored) / double(c.baked) : 0.0;
    const std::string how = c.baked == c.cells ? " (measured)" : " (from the rate)";
    rows.push_back({fixed(c.alpha_deg, 1) + "°", fixed(c.v, 2), std::to_string(c.cells), std::to_string(c.baked),
                    fixed(1e3 * per_cell_s, 0), fixed(per_cell_s * double(c.cells) / 60.0, 1) + how, fixed(c.cells_s, 2),
                    fixed(per_cell_bytes / 1024.0, 1), fixed(per_cell_bytes * double(c.cells) / kMiB, 1) + how,
                    fixed(c.baked ? double(c.sizes.raw_face_bytes) / double(stored) : 0.0, 1),
                    thesis && i < 2 ? std::string(thesis_figures[i][0]) + " m; " + thesis_figures[i][1] + "; " + thesis_figures[i][2] : "—"});
  }
  return rows;
}

const std::vector<std::string> kTable61Header = {
    "α", "v (m)", "cells", "baked", "bake ms / cell", "all cells, min", "near lists, s (all cells)",
    "stored KiB / cell", "all cells, MiB", "raw / stored", "thesis: v; preprocessing; storage"};

const std::vector<std::string> kFramesHeader = {"path", "strategy", "frame ms mean", "sd", "p95", "max", "speed-up vs brute",
                                                "ideal ms (loads out, Fig. 6-3)", "triangles / frame", "crossings",
                                                "stall frames (loaded a cell)", "largest crossing ms"};

const std::vector<std::string> kFidelityHeader = {
    "path", "strategy", "frames compared", "PSNR dB", "differing pixels mean %", "max %", "missed of visible",
    "largest missed, px of truth", "pixel error max px",
    "far angle max (measured)", "α", "frames over α"};

// The rows of one walked path: frame times, fidelity and per-frame figures, and the summary.
struct Report {
  Table frames_rows, fidelity_rows, per_frame, crossing_rows;
  Json summary = Json::object();  // path id -> walker label -> figures
};

// The walker's mean frame time over the frames numbered in `frames` that it drew.
double mean_on(const Walker& w, const std::set<int>& frames) {
  std::vector<double> ms;
  for (const FrameStats& f : w.frames)
    if (frames.count(f.frame)) ms.push_back(f.frame_ms);
  return bench::mean(ms);
}

const std::vector<std::string> kCrossingHeader = {"path", "strategy", "crossings", "change at crossings, mean",
                                                  "max", "change elsewhere, mean", "far angle max (measured)"};

// How much the image changes at a crossing against the frames without one (the camera moves in
// both), for a walker that tracked it.
struct CrossingChange {
  size_t crossings = 0;
  double mean_at = 0, max_at = 0, mean_elsewhere = 0;
};

CrossingChange crossing_change(const Walker& w) {
  std::vector<double> at, elsewhere;
  for (size_t i = 1; i < w.change.size(); ++i) (w.crossings[i] ? at : elsewhere).push_back(w.change[i]);
  return {at.size(), bench::mean(at), at.empty() ? 0.0 : *std::max_element(at.begin(), at.end()), bench::mean(elsewhere)};
}

// Adds the walkers' figures along path `path_id` to `r`; the first walker is brute force. A
// speed-up is over the frames brute force drew (every walker draws those), so walkers that draw
// more frames are compared on the same ones.
void report_walk(const std::vector<Walker>& walkers, const std::string& path_id, Report& r) {
  std::set<int> brute_frames;
  for (const FrameStats& f : walkers.front().frames) brute_frames.insert(f.frame);
  const double brute_ms = mean_on(walkers.front(), brute_frames);
  for (const Walker& w : walkers) {
    const FrameSummary s = summarize_frames(w);
    const double same_frames_ms = mean_on(w, brute_frames);
    const double speedup = same_frames_ms > 0 ? brute_ms / same_frames_ms : 0.0;
    r.frames_rows.push_back({path_id, w.label, fixed(s.mean, 2), fixed(s.sd, 2), fixed(s.p95, 2), fixed(s.max, 2),
                           fixed(speedup, 2) + "×", fixed(s.ideal_mean, 2),
                           std::to_string(s.triangles), std::to_string(s.crossings), std::to_string(s.loads),
                           fixed(s.max_load, 1)});
    const FidelitySummary f = summarize(w.fidelity);
    const double worst = w.angles.empty() ? 0.0 : *std::max_element(w.angles.begin(), w.angles.end());
    const auto over = std::count_if(w.angles.begin(), w.angles.end(), [&](double a) { return w.stratified && a > w.alpha; });
    r.fidelity_rows.push_back({path_id, w.label, std::to_string(f.frames),
                             std::isfinite(f.mean_psnr_db) ? fixed(f.mean_psnr_db, 1) : "inf",
                             fixed(100 * f.mean_differing_fraction, 3), fixed(100 * f.max_differing_fraction, 3),
                             std::to_string(f.missed_objects) + " of " + std::to_string(f.visible_objects),
                             std::to_string(f.largest_missed_pixels), fixed(f.max_pixel_error_px, 1), w.stratified ? fixed(deg(worst), 2) + "°" : "—",
                             w.stratified ? fixed(deg(w.alpha), 1) + "°" : "—", w.stratified ? std::to_string(over) : "—"});
    r.summary[path_id][w.label] = {
        {"frames", w.frames.size()}, {"frame_ms", s.mean}, {"frame_ms_on_brute_frames", same_frames_ms},
        {"speedup", speedup}, {"triangles", s.triangles},
        {"crossings", s.crossings}, {"stall_frames", s.loads}, {"max_far_angle_deg", deg(worst)}, {"frames_over_alpha", over},
        {"psnr_db", std::isfinite(f.mean_psnr_db) ? Json(f.mean_psnr_db) : Json(nullptr)},
        {"missed", f.missed_objects}, {"visible", f.visible_objects}};
    if (w.track_change) {
      const CrossingChange c = crossing_change(w);
      r.crossing_rows.push_back({path_id, w.label, std::to_string(c.crossings), fixed(c.mean_at, 2), fixed(c.max_at, 2),
                                 fixed(c.mean_elsewhere, 2), fixed(deg(worst), 2) + "°"});
      r.summary[path_id][w.label]["change_at_crossings"] = c.mean_at;
      r.summary[path_id][w.label]["change_elsewhere"] = c.mean_elsewhere;
    }
    for (size_t i = 0; i < w.frames.size(); ++i)
      r.per_frame.push_back({path_id, w.label, std::to_string(w.frames[i].frame), fixed(w.frames[i].frame_ms, 3),
                           std::to_string(w.frames[i].triangles), w.crossings[i] ? "1" : "0", w.frames[i].stall ? "1" : "0",
                           fixed(w.frames[i].io_ms + w.frames[i].decode_ms, 3), fixed(deg(w.angles[i]), 4)});
  }
}

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


// The city-scale run's world, path and preprocessing.
struct ScaleCity {
  std::string world_file;
  uint64_t objects = 0, triangles = 0;
  Vec3 size{0.0f};
  double build_s = 0;
  CameraPath path;
  Config config;
};

std::optional<ScaleCity> make_scale_city(const StratifiedBenchParams& p, const bench::WorkDir& dir) {
  if (p.scale_blocks <= 0) return std::nullopt;
  ScaleCity s;
  StratifiedCityParams city = p.city;
  city.blocks_x = city.blocks_z = p.scale_blocks;
  s.world_file = dir.file("scale.cww");
  bench::WorldBuild build;
  build.progress_label = "bench stratified: build the city-scale world";
  s.build_s = bench::make_bench_world(city, build, dir.file("scale.cwscene"), s.world_file).seconds;
  const World world(s.world_file);
  s.objects = world.object_count();
  s.triangles = world.triangle_count();
  s.size = world.info().bounds.size();
  PathParams path_params;
  path_params.kind = parse_session_kind(p.scale_path_kind);
  path_params.frames = p.scale_frames;
  path_params.seed = p.path_seeds.empty() ? 1 : p.path_seeds.front();
  s.path = generate_path(world.info().nav, path_params);
  const double alpha = p.alphas_deg.front();
  s.config = preprocess(p, world, s.path, alpha, dir.file("scale-alpha" + fixed(alpha, 1) + ".cww"));
  return s;
}

// Brute force, the scale strategies and stratified at the first α along the scale path,
// interleaved frame by frame; the figures go to `r` under the path id "scale".
// "1st", "2nd", "3rd", "12th": for the report's prose.
std::string ordinal(int n) {
  const int tens = n % 100, ones = n % 10;
  const char* suffix = tens >= 11 && tens <= 13 ? "th" : ones == 1 ? "st" : ones == 2 ? "nd" : ones == 3 ? "rd" : "th";
  return std::to_string(n) + suffix;
}

std::string stratified_label(double alpha_deg) { return "stratified-" + fixed(alpha_deg, 1); }

// Brute force and the scale strategies on every scale_others_every-th frame and stratified at
// the first α on every frame, interleaved; then stratified alone along the whole path, whose
// stall frames are the honest count (interleaved, its prefetcher has the other walkers' slow
// frames to load in). The figures go to `r` under the path id "scale".
void walk_scale_city(const StratifiedBenchParams& p, const ScaleCity& s, const Camera& lens, const fs::path& sub, Report& r) {
  std::vector<Walker> walkers;
  walkers.push_back(make_walker("brute", s.world_file, "brute", p, 0.0));
  for (const std::string& name : p.scale_strategies) walkers.push_back(make_walker(name, s.world_file, name, p, 0.0));
  for (Walker& w : walkers) w.every = p.scale_others_every;
  const double alpha = rad(s.config.alpha_deg);
  walkers.push_back(make_walker(stratified_label(s.config.alpha_deg), s.config.file, "stratified", p, alpha));
  walkers.back().images = true;
  Walker truth = make_walker("truth", s.world_file, "ground-truth", p, 0.0);
  walk_interleaved(walkers, truth, s.path, lens, p.scale_fidelity_every, p.images, sub, "scale-");
  std::vector<Walker> alone;
  alone.push_back(make_walker(stratified_label(s.config.alpha_deg) + "-alone", s.config.file, "stratified", p, alpha));
  walk_interleaved(alone, truth, s.path, lens, int(s.path.frames.size()), 0, sub, "scale-alone-");
  walkers.push_back(std::move(alone.front()));
  report_walk(walkers, "scale", r);
  write_file_atomically((sub / "frame-times-scale.svg").string(), frame_times_svg(walkers, p.scale_path_kind + " path at city scale"));
}

std::string scale_markdown(const StratifiedBenchParams& p, const ScaleCity& s, const Report& r) {
  const Json& walks = r.summary["scale"];
  const std::string strat = stratified_label(s.config.alpha_deg);
  std::string md = "\n## At city scale\n\n";
  md += "The same generator with " + std::to_string(p.scale_blocks) + " × " + std::to_string(p.scale_blocks) + " blocks: " +
        fixed(s.size.x, 0) + " × " + fixed(s.size.z, 0) + " × " + fixed(s.size.y, 0) + " m, " + std::to_string(s.objects) +
        " objects, " + std::to_string(s.triangles) + " triangles, built in " + fixed(s.build_s, 1) + " s. One " +
        p.scale_path_kind + " path of " + std::to_string(s.path.frames.size()) + " frames. Brute force takes " +
        fixed(walks["brute"]["frame_ms"].get<double>() / 1e3, 2) + " s a frame here, so it and the " +
        std::to_string(p.scale_strategies.size()) + " other strategies draw every " + ordinal(p.scale_others_every) +
        " frame, interleaved with `" + strat + "`, which draws every frame; every strategy draws the frames compared with "
        "ground truth (every " + ordinal(p.scale_fidelity_every) + "), and each speed-up is taken over the frames brute "
        "force drew. Interleaved, stratified's prefetcher has the slow frames to load in, so its stall frames are counted "
        "again on a walk of its own along the whole path (`" + strat + "-alone`). Only the cells within " +
        fixed(p.along_margin, 0) + " m of the path are baked.\n\n";
  md += bench::md_table(kTable61Header, table61({s.config}, false), bench::Align::kFigures);
  md += "\n" + bench::md_table(kFramesHeader, r.frames_rows, bench::Align::kFigures);
  md += "\n![frame times at city scale](stratified/frame-times-scale.svg)\n\n";
  md += bench::md_table(kFidelityHeader, r.fidelity_rows, bench::Align::kFigures);
  md += "\nStratified's speed-up over each, on the frames they drew, same run:";
  for (const auto& [label, w] : walks.items())
    if (label != strat && label != strat + "-alone")
      md += " " + label + " " +
            fixed(w["frame_ms_on_brute_frames"].get<double>() / walks[strat]["frame_ms_on_brute_frames"].get<double>(), 2) + "×;";
  md.back() = '.';
  md += "\n";
  return md;
}

}  // namespace

Json run_stratified_bench(const StratifiedBenchParams& p) {
  if (p.alphas_deg.empty()) fail("bench stratified", "give at least one --alpha");
  if (p.fidelity_every < 1 || p.frames < 1) fail("bench stratified", "--frames and --fidelity-every must be at least 1");
  std::set<std::string> scale_names;
  for (const std::string& name : p.scale_strategies) {
    check_strategy_name(name);
    if (name == "brute" || name == "ground-truth" || name.rfind("stratified", 0) == 0 || !scale_names.insert(name).second)
      fail("bench stratified", "--scale-strategy " + name + ": brute, ground truth and stratified are walked anyway; give "
                               "each other strategy once");
  }
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
  const std::optional<ScaleCity> scale = make_scale_city(p, dir);

  const std::unique_ptr<GlContext> context = GlContext::headless();
  Camera lens;
  lens.fov_y_deg = float(p.fov_deg);
  lens.aspect = float(p.width) / float(p.height);
  const fs::path out = fs::path(p.out_dir), sub = out / "stratified";
  fs::create_directories(sub);
  Report report;
  for (const auto& [seed, path] : paths) {
    const std::string path_name = p.path_kind + " path, seed " + std::to_string(seed);
    std::vector<Walker> walkers;
    walkers.push_back(make_walker("brute", world_file, "brute", p, 0.0));
    for (const Config& c : configs) {
      walkers.push_back(make_walker("stratified-" + fixed(c.alpha_deg, 1), c.file, "stratified", p, rad(c.alpha_deg)));
      walkers.back().images = true;  // the -noprefetch runs draw the same images
      walkers.back().track_change = p.fade_frames > 0;
      if (p.fade_frames == 0) continue;
      const std::string fade = "fade=" + std::to_string(p.fade_frames);
      walkers.push_back(make_walker("stratified-" + fixed(c.alpha_deg, 1) + "-" + fade, c.file, "stratified:" + fade, p,
                                    rad(c.alpha_deg)));
      walkers.back().track_change = true;
    }
    // The thesis's own run time: every crossing loads in its frame.
    for (const Config& c : configs)
      walkers.push_back(make_walker("stratified-" + fixed(c.alpha_deg, 1) + "-noprefetch", c.file, "stratified:prefetch=0", p,
                                    rad(c.alpha_deg)));
    Walker truth = make_walker("truth", world_file, "ground-truth", p, 0.0);
    walk_interleaved(walkers, truth, path, lens, p.fidelity_every, p.images, sub, "seed" + std::to_string(seed) + "-");
    report_walk(walkers, std::to_string(seed), report);
    write_file_atomically((sub / ("frame-times-seed" + std::to_string(seed) + ".svg")).string(), frame_times_svg(walkers, path_name));
  }
  Report scale_report;
  if (scale) walk_scale_city(p, *scale, lens, sub, scale_report);
  const Table t61 = table61(configs, true);
  bench::write_csv(sub / "table61.csv", kTable61Header, t61);
  Table per_frame = report.per_frame;
  per_frame.insert(per_frame.end(), scale_report.per_frame.begin(), scale_report.per_frame.end());
  bench::write_csv(sub / "frames.csv",
                   {"path", "strategy", "frame", "frame_ms", "triangles", "crossing", "stall", "load_ms", "far_angle_deg"}, per_frame);

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
        "sees much). An α with at most " + std::to_string(p.bake_all_up_to) + " cells is baked whole, so its row of "
        "Table 6.1 is measured; a larger one only within " + fixed(p.along_margin, 0) + " m of the paths, and its "
        "preprocessing and storage for every cell are projected from the measured rate. Baking runs on " +
        std::to_string(p.bake_threads) + " threads, each with a GL context of its own. " +
        (p.far_level_texels > 0
             ? "Far objects are baked at the coarsest level whose error covers under " + fixed(p.far_level_texels, 2) +
                   " texel (`--far-level-texels`; the thesis drew full detail, `--far-level-texels 0`).\n\n"
             : std::string("Far objects are baked at full detail, as the thesis did.\n\n"));
  md += "## Table 6.1\n\n" + bench::md_table(kTable61Header, t61, bench::Align::kFigures);
  md += "\n## Frame time (Figs. 6-1 to 6-3)\n\n" + bench::md_table(kFramesHeader, report.frames_rows, bench::Align::kFigures);
  for (const auto& [seed, path] : paths)
    md += "\n![frame times, seed " + std::to_string(seed) + "](stratified/frame-times-seed" + std::to_string(seed) + ".svg)\n";
  md += "\n`-noprefetch` is the thesis's run time: a crossing loads the "
        "new cell's near list and far faces in its frame (a stall frame); 'ideal' takes those loads out (Fig. 6-3). "
        "Without the suffix, a thread loads the cells the viewer's velocity reaches within 1.5 s, so a crossing finds its "
        "cell loaded; a stall frame is one that had to load its cell or wait for the prefetcher.\n";
  md += "\n## Fidelity against ground truth, and the far field's angular error\n\n" +
        bench::md_table(kFidelityHeader, report.fidelity_rows, bench::Align::kFigures);
  md += "\nEvery " + std::to_string(p.fidelity_every) +
        "th frame is compared. The far angle is measured on every frame: the largest angle, over the far texels in view, "
        "between where the far point is (from the stored depth) and where its face shows it, seen from the eye. "
        "Difference images (128 + test − truth, the thesis's Figs. 6-4 to 6-7) are in `stratified/frame*-diff.png`.\n";
  if (p.fade_frames > 0) {
    md += "\n## Crossings: the hard switch and the cross-fade\n\n" + bench::md_table(kCrossingHeader, report.crossing_rows, bench::Align::kFigures);
    md += "\nChange: the mean absolute difference of a frame's colour channels (0–255) from the frame before. At a crossing "
          "the far field jumps by up to 2α as the faces of the next cell replace the last's; `fade=" + std::to_string(p.fade_frames) +
          "` blends the last cell's faces over the new ones at falling opacity for " + std::to_string(p.fade_frames) +
          " frames (the object ids stay the new cell's), so the jump is spread over them. Its far angle counts the fading "
          "faces too, seen from outside their cell.\n";
  }
  if (scale) md += scale_markdown(p, *scale, scale_report);
  write_file_atomically((out / "stratified.md").string(), md);
  Json summary = {{"world", {{"objects", world.object_count()}, {"triangles", world.triangle_count()}}},
                  {"far_level_texels", p.far_level_texels}, {"paths", report.summary}};
  for (const Config& c : configs)
    summary["table61"].push_back({{"alpha_deg", c.alpha_deg}, {"cells", c.cells}, {"baked", c.baked}, {"bake_seconds", c.bake_s},
                                  {"stored_bytes", c.sizes.color_bytes + c.sizes.id_bytes + c.sizes.depth_bytes},
                                  {"color_bytes", c.sizes.color_bytes}});
  if (scale)
    summary["scale"] = {{"objects", scale->objects}, {"triangles", scale->triangles}, {"walks", scale_report.summary["scale"]}};
  return summary;
}

}  // namespace cellwalk
