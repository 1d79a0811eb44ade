// cellwalk bench pvs-stream: Zheng's §7.5 simulation, Table 7.2 (experiments/pvs_stream/pvs_stream_report.hpp).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/path_generator.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "experiments/pvs_stream/pvs_stream_report.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_bench_pvs_stream(CLI::App& bench, std::string (*command_line)()) {
  auto* cmd = bench.add_subcommand(
      "pvs-stream", "Zheng ch. 7: SNP against PBNP prefetch of PVS rows, Table 7.2 in simulation -> <out>/pvs-stream.md");
  struct Args {
    PvsStreamBenchParams params;
    bool json = false;
    bool no_sockets = false;
  };
  auto args = std::make_shared<Args>();
  PvsStreamBenchParams& p = args->params;
  cmd->add_option("--blocks", p.city.blocks, "Buildings along each side of the city (the thesis: 30)")->capture_default_str()->check(integer_in(2, 1000));
  cmd->add_option("--visible", p.city.visible, "Fraction of the objects a view cell sees (the thesis: 0.05)")->capture_default_str()->check(number_in(1e-6, 1));
  cmd->add_option("--blob-min", p.city.blob_min, "Smallest side, in cells, of a rectangle seeing an object")->capture_default_str()->check(integer_in(1, 100));
  cmd->add_option("--blob-max", p.city.blob_max, "Largest side, in cells, of a rectangle seeing an object")->capture_default_str()->check(integer_in(1, 100));
  cmd->add_option("--city-seed", p.city.seed, "Seed of the synthetic PVS table")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--steps", p.route.steps, "Steps of each route (the thesis: 3000)")->capture_default_str()->check(integer_in(1, 10000000));
  cmd->add_option("--route-seed", p.route.seed, "Seed of route 1 in Table 7.2")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--seeds", p.seeds, "Further seeds of route 1")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--band", p.band, "PBNP's region band, a fraction of a cell")->capture_default_str()->check(number_in(0.001, 0.499));
  cmd->add_option("--bands", p.bands, "Bands swept for PBNP")->capture_default_str()->check(number_in(0.001, 0.499));
  cmd->add_flag("--no-sockets", args->no_sockets, "Only the simulation: no walks over sockets");
  cmd->add_option("--net-objects", p.net.objects, "Sockets: buildings of the city walked")->capture_default_str()->check(integer_in(4, 1000000));
  cmd->add_option("--net-city-seed", p.net.city_seed, "Sockets: the city's seed")->capture_default_str()->check(integer_in(0, INT64_MAX));
  cmd->add_option("--net-cell", p.net.cell, "Sockets: side of a view cell, m")->capture_default_str()->check(number_in(1, 1000));
  cmd->add_option("--net-frames", p.net.frames, "Sockets: frames of each path (30 per second)")->capture_default_str()->check(integer_in(2, 1000000));
  cmd->add_option("--net-paths", p.net.kinds, "Sockets: path kinds walked (normal, fast, ...)")->capture_default_str();
  cmd->add_option("--latencies", p.net.latencies, "Sockets: one-way delays, ms, each direction")->capture_default_str()->check(number_in(0, 10000));
  cmd->add_option("--bandwidths", p.net.bandwidths, "Sockets: rates, Mbit/s, each direction (0: unlimited)")->capture_default_str()->check(number_in(0, 1e6));
  cmd->add_option("--prefetchers", p.net.prefetchers, "Sockets: snp, pbnp, speed")->capture_default_str()->check(CLI::IsMember({"snp", "pbnp", "speed"}));
  cmd->add_option("--nginx-prefetchers", p.net.nginx_prefetchers, "Sockets: the prefetchers walked again with the world on nginx (range requests); none: give --nginx-prefetchers with no value")
      ->capture_default_str()->expected(0, -1)->check(CLI::IsMember({"snp", "pbnp", "speed"}));
  cmd->add_option("--clients", p.net.clients, "Sockets: clients on one server (0: none)")->capture_default_str()->check(integer_in(0, 1000));
  cmd->add_option("--work-dir", p.net.work_dir, "Sockets: where the city and its sets go (default: a temporary folder)");
  cmd->add_option("--out", p.out_dir, "Directory of the report (pvs-stream.md and pvs-stream/)")->capture_default_str();
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args, command_line] {
    if (args->params.city.blob_max < args->params.city.blob_min)
      throw Error("bench pvs-stream: --blob-max " + std::to_string(args->params.city.blob_max) + " is below --blob-min " +
                  std::to_string(args->params.city.blob_min) + "; give a max at least the min");
    for (const std::string& kind : args->params.net.kinds) parse_session_kind(kind);  // a bad name fails before any work
    args->params.sockets = !args->no_sockets;
    args->params.command_line = command_line();
    const nlohmann::ordered_json summary = run_pvs_stream_bench(args->params);
    if (args->json) {
      print_json("bench pvs-stream", summary);
      return;
    }
    std::printf("%u view cells, %u objects: a cell sees %.2f %%, neighbours share %.1f %%\n",
                summary["view_cells"].get<uint32_t>(), summary["objects"].get<uint32_t>(),
                100 * summary["visible_fraction"].get<double>(), 100 * summary["adjacent_overlap"].get<double>());
    for (const auto& r : summary["routes"])
      std::printf("%-28s SNP %5llu transactions %6llu swaps | PBNP %5llu transactions %6llu swaps\n",
                  r["route"].get<std::string>().c_str(), (unsigned long long)r["snp"]["transactions"].get<uint64_t>(),
                  (unsigned long long)r["snp"]["cache_swaps"].get<uint64_t>(),
                  (unsigned long long)r["pbnp"]["transactions"].get<uint64_t>(),
                  (unsigned long long)r["pbnp"]["cache_swaps"].get<uint64_t>());
    if (!summary["sockets"].is_null())
      std::printf("over sockets: PBNP fewer rows replaced than SNP everywhere: %s; 80 ms / 100 Mbit/s target: %s\n",
                  summary["sockets_pbnp_fewer_swaps"].get<bool>() ? "yes" : "NO", summary["sockets_target_met"].get<bool>() ? "met" : "MISSED");
    std::printf("wrote %s/pvs-stream.md in %.1f s\n", args->params.out_dir.c_str(), summary["seconds"].get<double>());
  });
}

}  // namespace cellwalk::app
