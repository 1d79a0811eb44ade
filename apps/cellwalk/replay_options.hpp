// Options of the commands that replay a path with a strategy (walk, compare): the world, the
// path, the strategy and its memory budget, where to write, and the lens.
#pragma once

#include <CLI/CLI.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cellwalk/core/error.hpp"

#include "cellwalk/render/renderer.hpp"
#include "cellwalk/runtime/run_budget.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/strategy/strategy.hpp"
#include "cellwalk/store/world.hpp"
#include "checks.hpp"
#include "lens_options.hpp"

namespace cellwalk::app {

struct ReplayOptions {
  std::string world, path, out;
  std::vector<std::string> strategies{"brute"};  // several: run one after another, side by side
  double budget_mib = 0;
  double eta = 0.001;
  uint64_t polygon_budget = 20000;
  bool no_dov_levels = false;
  std::string objects_db;
  bool json = false;
  bool bypass_cache = false;
  double read_latency_ms = 0;
  LensOptions lens;

  void add_to(CLI::App& cmd, const std::string& default_out) {
    out = default_out;
    cmd.add_option("world", world, "World file (.cww) from cellwalk build")->required();
    cmd.add_option("--path", path, "Camera path file (cellwalk path)")->required();
    cmd.add_option("--strategy", strategies,
                   "Strategy: " + CLI::detail::join(strategy_names()) +
                       "; repeat to run several on the same path and compare them in one table")
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
        ->capture_default_str();
    cmd.add_option("-o,--output", out, "Output folder")->capture_default_str();
    cmd.add_option("--budget", budget_mib, "Memory budget, MiB (0 = none): all that grows with the world and the path; walk holds the process to it plus the baseline it reports, and rasterises on its own thread (docs/design.md, Memory)")
        ->capture_default_str()
        ->check(number_in(0, 1 << 24));
    cmd.add_option("--eta", eta, "hdov-vsc: DoV threshold η (HDoV thesis §5.3)")->capture_default_str()->check(number_in(0, 1));
    cmd.add_option("--polygon-budget", polygon_budget, "hdov-pb: triangles per frame (HDoV thesis §6.1.2)")->capture_default_str()->check(integer_in(1, 1000000000));
    cmd.add_flag("--no-dov-levels", no_dov_levels, "hdov-vsc, hdov-pb: no level lowered by DoV (eq. 5.6, PB's λ)");
    cmd.add_option("--objects-db", objects_db,
                   "Read objects from this object database (cellwalk db WORLD) instead of the world file");
    cmd.add_flag("--json", json, "Print the summary as JSON");
    cmd.add_flag("--bypass-cache", bypass_cache, "Read the world around the OS page cache (O_DIRECT, else drop-behind)");
    cmd.add_option("--read-latency-ms", read_latency_ms, "A slow disk: wait this long before every read of the world, ms")
        ->capture_default_str()
        ->check(number_in(0, 1000));
    lens.add_to(cmd);
  }
  // How the world is opened: through the page cache or around it, at the disk's speed or slower.
  WorldFile::Options world_options() const {
    return {.bypass_cache = bypass_cache, .read_latency_us = static_cast<uint32_t>(read_latency_ms * 1000.0 + 0.5)};
  }
  // The checks of a replay before any work: the lens, an output folder that is not an input
  // file, and the path's world (a warning: a path may be reused on purpose).
  CameraPath read_checked_path(const World& opened) const {
    lens.check();
    refuse_same_files(objects_db.empty() ? std::vector<std::string>{world, path} : std::vector<std::string>{world, path, objects_db}, {out});
    CameraPath p = read_path(path);
    warn_if_other_world(p, path, opened.info(), world);
    return p;
  }
  // Creates the output folder, before any work, so a bad --output fails at once; the folders it
  // made are removed again if the run fails before writing into them (OutputFolder).
  OutputFolder make_output_folder() const { return OutputFolder(out); }
  // Checks every --strategy's name and settings before any run, so a typo fails at once.
  void check_strategies() const;
  // A run held to a budget rasterises on its own thread (renderer.hpp, Rasteriser).
  Rasteriser rasteriser() const { return budget_mib > 0 ? Rasteriser::kCallingThread : Rasteriser::kWorkerThreads; }

  // The budget of a run over `frames` frames: --budget is the process's (run_budget.hpp).
  RunBudget run_budget(size_t frames) const {
    const std::optional<uint64_t> gpu =
        lens.gpu_budget_given() ? std::optional<uint64_t>(lens.render_settings().gpu_budget_bytes) : std::nullopt;
    return split_run_budget(static_cast<uint64_t>(budget_mib * 1024 * 1024), frames, gpu);
  }
  RenderSettings render_settings(const RunBudget& budget) const {
    RenderSettings s = lens.render_settings();
    if (budget.total_bytes > 0) s.gpu_budget_bytes = budget.gpu_bytes;
    return s;
  }
  // One run of a --strategy: its strategy, made once, right before the run, and released after
  // it (so runs never hold memory at once). The label is the strategy's own name (its settings
  // spelled out), or the text as given where two --strategy of one family (the text before
  // ':') could share a name — REVIEW's settings are not all in its name — or an earlier run
  // already has it.
  struct Run {
    std::string label;
    std::unique_ptr<Strategy> strategy;
  };
  Run make_run(const std::string& given, const World& world, const RunBudget& budget,
               std::vector<std::string>& labels_used) const;
  StrategyOptions strategy_options(const RunBudget& budget) const {
    StrategyOptions options;
    options.memory_budget_bytes = budget.strategy_bytes;
    options.viewport_height_px = float(lens.height);
    options.eta = eta;
    options.polygon_budget = polygon_budget;
    options.dov_levels = !no_dov_levels;
    options.objects_db = objects_db;
    return options;
  }
};

}  // namespace cellwalk::app
