// cellwalk bench: measurements that write the reports under docs/results/ (DESIGN.md
// "Measuring"). A parent command: each measured component adds a subcommand here.
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/store/store_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {
namespace {

// The command line as typed (from /proc, as CLI11 keeps no copy), recorded in the report so
// anyone can regenerate it. The program's path is shown as plain "cellwalk".
std::string command_line() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string line = "cellwalk", arg;
  std::getline(in, arg, '\0');
  while (std::getline(in, arg, '\0')) line += " " + arg;
  return line;
}

void register_store(CLI::App& bench) {
  auto* cmd = bench.add_subcommand(
      "store", "World store: build, reads, decode, cache policies -> <out>/store.md");
  struct Args {
    StoreBenchParams params;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  StoreBenchParams& p = args->params;
  cmd->add_option("--objects", p.objects, "Objects of the generated city measured")
      ->capture_default_str()->check(number_in(1, 1e7));
  cmd->add_flag("--large", p.large,
                "Also generate and build a ~10^8-triangle city (long; needs ~6 GB of disk)");
  cmd->add_option("--large-objects", p.large_objects, "Objects of the --large city")
      ->capture_default_str()->check(number_in(1, 1e7));
  cmd->add_option("--threads", p.threads, "Build threads (0 = all cores)")->capture_default_str()->check(thread_count());
  cmd->add_option("--frames", p.path_frames, "Frames of the walk recorded as the cache trace")
      ->capture_default_str()
      ->check(number_in(0, 1e12, true));
  cmd->add_option("--rounds", p.io_rounds, "Interleaved rounds of each read and decode measurement")
      ->capture_default_str()
      ->check(number_in(0, 1e12, true));
  cmd->add_option("--random-reads", p.random_reads, "Random 4 KiB reads per method and round")
      ->capture_default_str()
      ->check(number_in(0, 1e12, true));
  cmd->add_option("--sequential-bytes", p.sequential_bytes, "Bytes per sequential read pass")
      ->capture_default_str();
  cmd->add_option("--budgets", p.budget_fractions,
                  "Cache budgets as fractions of the trace's working set")
      ->capture_default_str()
      ->check(number_in(1e-6, 1.0));
  cmd->add_option("--out", p.out_dir, "Directory of the report (store.md and store/)")
      ->capture_default_str();
  cmd->add_option("--work-dir", p.work_dir,
                  "Where the scene and world files go (default: a temporary directory)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args] {
    args->params.command_line = command_line();
    const nlohmann::ordered_json summary = run_store_bench(args->params);
    if (args->json) {
      print_json("bench store", summary);
      return;
    }
    for (const auto& sentence : summary["reading"])
      std::printf("%s\n", sentence.get<std::string>().c_str());
    std::printf("wrote %s/store.md\n", args->params.out_dir.c_str());
  });
}

}  // namespace

void register_bench(CLI::App& root) {
  auto* bench =
      root.add_subcommand("bench", "Measure a component and write its report under docs/results/");
  bench->require_subcommand(1);
  register_store(*bench);
  register_bench_scene_tree(*bench, command_line);
  register_bench_review(*bench, command_line);
  register_bench_visual(*bench, command_line);
  register_bench_visibility(*bench, command_line);
  register_bench_vlod(*bench, command_line);
  register_bench_stratified(*bench, command_line);
  register_bench_lichiang(*bench, command_line);
  register_bench_vdr(*bench, command_line);
  register_bench_disk_order(*bench, command_line);
  register_bench_import(*bench, command_line);
  register_bench_pvs_stream(*bench, command_line);
}

}  // namespace cellwalk::app
