// `cellwalk bench visual`, Exp. 3: HDoV thesis §5.8.5 (digest §5.5, Table 5.3, Figs. 5.24–5.27),
// VISUAL against REVIEW on one path, with the fidelity of each through the compare harness.
#include "experiments/visual/visual_walks.hpp"

#include <functional>
#include <memory>

#include "cellwalk/metrics/fidelity.hpp"
#include "cellwalk/metrics/walk_summary.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/systems/visual/visual_strategy.hpp"
#include "cellwalk/render/renderer.hpp"
#include "cellwalk/systems/review/review.hpp"
#include "cellwalk/strategy/strategy.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"

namespace cellwalk::visual_bench {
namespace {

Camera lens_of(const VisualBenchParams& p) {
  Camera camera;
  camera.fov_y_deg = 45;
  camera.aspect = float(p.width) / float(p.height);
  camera.near_plane = 0.5f;
  camera.far_plane = 400.0f;
  return camera;
}

// Replays `path` headless: frame time = the strategy's select and mesh calls (query, I/O,
// decode) + triangles / the modelled render rate; the same for every strategy.
void replay(Strategy& s, const CameraPath& path, const VisualBenchParams& p, WalkRun& run) {
  Camera camera = lens_of(p);
  for (const PathFrame& f : path.frames) {
    apply(f, camera);
    const bench::SelectedFrame frame = bench::select_frame(s, camera, f.time);
    run.triangles += frame.triangles;
    run.frame_ms.push_back(frame.select_ms + double(frame.triangles) / (p.render_mtri_per_s * 1e3));
  }
  run.peak = s.peak_resident_bytes();
}

// `full`: MAXDOV of eq. 5.6 so small that k = 1 for every visible object (level 0), what
// `visual:eta=X,maxdov=0.000000001` gives in `cellwalk walk` / `compare`.
VisualConfig visual_config(const TreeWorld& w, double eta, bool full) {
  VisualConfig config;
  config.eta = eta;
  if (full) config.max_dov = 1e-9;
  config.tree_file = w.tree_file;
  return config;
}

ReviewConfig review_config() {
  ReviewConfig rc;
  rc.depth = 400;  // the thesis's 400 m query boxes
  return rc;
}

}  // namespace

std::vector<WalkRun> run_walks(const VisualBenchParams& p, const TreeWorld& w, const CameraPath& path) {
  std::vector<WalkRun> runs;
  // Each run's strategy is made twice, fresh: once for the timed replay, once for the fidelity.
  std::vector<std::function<std::unique_ptr<Strategy>()>> makers;
  for (bool full : {false, true})
    for (double eta : p.walk_etas) {
      runs.push_back({.label = std::string(full ? "VISUAL-full" : "VISUAL") + " η=" + bench::fixed(eta, 4), .eta = eta, .full = full});
      makers.push_back([&w, eta, full] { return std::make_unique<VisualStrategy>(*w.world, visual_config(w, eta, full), StrategyOptions{}); });
    }
  runs.push_back({.label = "REVIEW (400 m)"});
  makers.push_back([&w] { return std::make_unique<ReviewStrategy>(*w.world, review_config(), StrategyOptions{}); });

  Progress progress("Exp. 3 walks", runs.size());
  for (size_t i = 0; i < runs.size(); ++i) {
    const std::unique_ptr<Strategy> s = makers[i]();
    replay(*s, path, p, runs[i]);
    const QueryTotals q = s->query_totals();
    runs[i].queries = q.queries, runs[i].ios = q.disk_ios, runs[i].query_ms = q.ms;
    progress.update(i + 1);
  }
  progress.finish();

  // Fidelity as compare() measures it (render_frame + compare_images), with the ground truth of
  // each compared frame rendered once for all systems: it costs the most (every object at level 0).
  const auto context = GlContext::headless();
  RenderSettings render;
  render.width = p.width;
  render.height = p.height;
  Renderer renderer(render);
  const std::unique_ptr<Strategy> truth = make_strategy("ground-truth", *w.world, {});
  std::vector<std::unique_ptr<Strategy>> systems;
  for (const auto& make : makers) systems.push_back(make());
  std::vector<std::vector<FidelityFrame>> frames(runs.size());
  Progress compared("Exp. 3 fidelity", path.frames.size());
  Camera camera = lens_of(p);
  for (size_t f = 0; f < path.frames.size(); f += size_t(p.fidelity_every)) {
    apply(path.frames[f], camera);
    render_frame(*truth, renderer, camera, path.frames[f].time);
    const Image truth_color = renderer.read_color();
    const IdImage truth_ids = renderer.read_ids();
    for (size_t i = 0; i < systems.size(); ++i) {
      render_frame(*systems[i], renderer, camera, path.frames[f].time);
      frames[i].push_back(compare_images(truth_color, truth_ids, renderer.read_color(), renderer.read_ids(), nullptr));
      frames[i].back().frame = int(f);
    }
    compared.update(f + 1);
  }
  compared.finish();
  for (size_t i = 0; i < runs.size(); ++i) runs[i].fidelity = summarize(frames[i]);
  return runs;
}

}  // namespace cellwalk::visual_bench
