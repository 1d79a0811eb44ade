// cellwalk bench vdr: Zheng's chapters 3–6 (seed 004) on the CGAL models and a generated large
// mesh (experiments/vdr/vdr_report.hpp).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "checks.hpp"
#include "commands.hpp"
#include "experiments/vdr/vdr_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_vdr(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand(
      "vdr", "View-dependent rendering over networks (seed 004, ch. 3–6): DAGs, traversals, LAN, WAN, many clients -> <out>/vdr.md");
  struct Args {
    VdrBenchParams params;
    bool json = false, no_render = false;
  };
  auto args = std::make_shared<Args>();
  VdrBenchParams& p = args->params;
  cmd->add_option("--model", p.models, "Model files (a bare name: data/cgal/meshes)")->capture_default_str();
  cmd->add_option("--large-triangles", p.large_triangles, "Also a generated bumpy sphere of about this many triangles (0: none)")
      ->capture_default_str()->check(integer_in(0, 100'000'000));
  cmd->add_option("--base-triangles", p.base_triangles, "Base mesh size of each progressive mesh")->capture_default_str()->check(integer_in(4, 10'000'000));
  cmd->add_option("--budget", p.budget, "B, the client's triangle budget")->capture_default_str()->check(integer_in(1, 1'000'000'000));
  cmd->add_option("-n,--ops", p.n, "N, ops per direction per frame")->capture_default_str()->check(integer_in(1, 65535));
  cmd->add_option("--tau", p.tau, "τ, a fraction of the viewport")->capture_default_str()->check(number_in(1e-6, 1));
  cmd->add_option("--units", p.units, "Error units: thesis (raw quadric error) or length")->capture_default_str()
      ->check(CLI::IsMember({"thesis", "length"}));
  cmd->add_option("--rtt", p.rtts, "Round-trip times of Table 6.1, ms")->capture_default_str()->check(number_in(0, 10000));
  cmd->add_option("--span", p.spans, "Fixed spans of Fig. 6.8 (at the second RTT, on the last model)")->capture_default_str()->check(integer_in(1, 64));
  cmd->add_option("--frame-ms", p.frame_ms, "Frames of Table 6.1 last at least this")->capture_default_str()->check(number_in(0, 10000));
  cmd->add_flag("--no-render", args->no_render, "Draw nothing (T_r = 0): no OpenGL needed");
  cmd->add_option("--clients", p.clients, "Clients on one server at the end (0: none)")->capture_default_str()->check(integer_in(0, 4096));
  cmd->add_option("--clients-rtt", p.clients_rtt, "Their round-trip time, ms")->capture_default_str()->check(number_in(0, 10000));
  cmd->add_option("--alone", p.alone, "Of them, walked again alone")->capture_default_str()->check(integer_in(0, 4096));
  cmd->add_option("--width", p.width, "Image width")->capture_default_str()->check(integer_in(16, 4096));
  cmd->add_option("--height", p.height, "Image height")->capture_default_str()->check(integer_in(16, 4096));
  cmd->add_option("--out", p.out_dir, "Directory of the report (vdr.md and vdr/)")->capture_default_str();
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    args->params.command_line = command_line();
    args->params.render = !args->no_render;
    const nlohmann::ordered_json summary = run_vdr_bench(args->params);
    if (args->json) {
      print_json("bench vdr", summary);
      return;
    }
    std::printf("%d models in %.1f min\nwrote %s/vdr.md\n", summary["models"].get<int>(), summary["minutes"].get<double>(),
                args->params.out_dir.c_str());
  });
}

}  // namespace cellwalk::app
