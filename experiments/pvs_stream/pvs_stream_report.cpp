// `cellwalk bench pvs-stream`: Zheng's §7.5 simulation (seed 004); see pvs_stream_report.hpp.
#include "experiments/pvs_stream/pvs_stream_report.hpp"

#include <algorithm>
#include <filesystem>
#include <optional>

#include "cellwalk/core/atomic_file.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"
#include "experiments/common/svg_plot.hpp"

namespace cellwalk {
namespace {

namespace fs = std::filesystem;
using bench::fixed;
using Json = nlohmann::ordered_json;
using namespace pvs_stream;

// Table 7.2 and §7.5's text (digest §5): route 1 SNP, route 1 PBNP, route 2 SNP, route 2 PBNP.
struct ThesisColumn {
  const char *transactions, *swaps, *per_transaction, *first;
};
const ThesisColumn kThesis[4] = {{"585", "1,785", "30", "158"}, {"487", "876", "16", "87"},
                                 {"600", "1,797", "29", "153"}, {"600", "828", "16", "51"}};

Json result_json(const SimulationResult& r) {
  return {{"transactions", r.transactions}, {"cache_swaps", r.cache_swaps}, {"evictions", r.evictions},
          {"objects_sent", r.objects_sent}, {"objects_per_transaction", r.objects_per_transaction()},
          {"first_prefetch", r.first_prefetch}, {"peak_objects", r.peak_objects}, {"border_checks", r.border_checks}};
}

PlotSeries step_series(const std::string& name, const SimulationResult& r) {
  PlotSeries s{name, {}};
  for (size_t i = 0; i < r.objects_per_step.size(); ++i) s.points.push_back({double(i), double(r.objects_per_step[i])});
  return s;
}

struct RouteRun {
  std::string name;
  std::vector<Point2> route;
  SimulationResult snp, pbnp;
};

std::string table72(const RouteRun runs[2]) {
  const std::vector<std::string> header{"", "route 1 SNP", "thesis", "route 1 PBNP", "thesis",
                                        "route 2 SNP", "thesis", "route 2 PBNP", "thesis"};
  bench::Table rows(6);
  rows[0] = {"prefetch transactions"};
  rows[1] = {"cache swaps (rows brought in)"};
  rows[2] = {"objects per transaction"};
  rows[3] = {"first prefetch (objects)"};
  rows[4] = {"rows replaced"};
  rows[5] = {"most objects held"};
  for (int k = 0; k < 4; ++k) {
    const SimulationResult& r = k % 2 == 0 ? runs[k / 2].snp : runs[k / 2].pbnp;
    const ThesisColumn& t = kThesis[k];
    const std::string ours[6] = {std::to_string(r.transactions), std::to_string(r.cache_swaps),
                                 fixed(r.objects_per_transaction(), 1), std::to_string(r.first_prefetch),
                                 std::to_string(r.evictions), std::to_string(r.peak_objects)};
    const char* theirs[6] = {t.transactions, t.swaps, t.per_transaction, t.first, "–", "–"};
    for (int i = 0; i < 6; ++i) {
      rows[i].push_back(ours[i]);
      rows[i].push_back(theirs[i]);
    }
  }
  return bench::md_table(header, rows, bench::Align::kFigures);
}

}  // namespace

Json run_pvs_stream_bench(const PvsStreamBenchParams& p) {
  const auto start = bench::Clock::now();
  const Json machine = bench::machine_info();
  Progress progress("pvs-stream", 2 + p.seeds.size() + p.bands.size());
  uint64_t done = 0;
  const SyntheticCity city = make_synthetic_city(p.city);
  progress.update(++done);

  RouteParams route_params = p.route;
  RouteRun runs[2] = {{"route 1 (random)", random_route(city, route_params), {}, {}},
                      {"route 2 (7 straight pieces)", straight_route(city, route_params), {}, {}}};
  for (RouteRun& run : runs) {
    run.snp = simulate(city, run.route, PrefetchAlgorithm::snp, p.band);
    run.pbnp = simulate(city, run.route, PrefetchAlgorithm::pbnp, p.band);
  }
  progress.update(++done);

  // Route 1 over several seeds: does the ordering hold for other random walks?
  const std::vector<std::string> seed_header{"route seed", "SNP transactions", "PBNP transactions", "SNP swaps",
                                             "PBNP swaps", "PBNP / SNP swaps", "SNP objects / transaction",
                                             "PBNP objects / transaction"};
  bench::Table seed_rows;
  Json seeds = Json::array();
  bool pbnp_fewer_swaps_every_seed = true;
  for (uint64_t seed : p.seeds) {
    RouteParams rp = p.route;
    rp.seed = seed;
    const std::vector<Point2> route = random_route(city, rp);
    const SimulationResult snp = simulate(city, route, PrefetchAlgorithm::snp, p.band);
    const SimulationResult pbnp = simulate(city, route, PrefetchAlgorithm::pbnp, p.band);
    pbnp_fewer_swaps_every_seed = pbnp_fewer_swaps_every_seed && pbnp.cache_swaps < snp.cache_swaps;
    seed_rows.push_back({std::to_string(seed), std::to_string(snp.transactions), std::to_string(pbnp.transactions),
                         std::to_string(snp.cache_swaps), std::to_string(pbnp.cache_swaps),
                         fixed(double(pbnp.cache_swaps) / double(std::max<uint64_t>(snp.cache_swaps, 1)), 2),
                         fixed(snp.objects_per_transaction(), 1), fixed(pbnp.objects_per_transaction(), 1)});
    seeds.push_back({{"seed", seed}, {"snp", result_json(snp)}, {"pbnp", result_json(pbnp)}});
    progress.update(++done);
  }

  // PBNP's band: the thesis gives no region widths (digest §3.10).
  const std::vector<std::string> band_header{"band (of a cell)", "route", "transactions", "cache swaps",
                                             "objects / transaction", "first prefetch", "most objects held"};
  bench::Table band_rows;
  Json bands = Json::array();
  for (double band : p.bands) {
    for (const RouteRun& run : runs) {
      const SimulationResult r = simulate(city, run.route, PrefetchAlgorithm::pbnp, band);
      band_rows.push_back({fixed(band, 2), run.name, std::to_string(r.transactions), std::to_string(r.cache_swaps),
                           fixed(r.objects_per_transaction(), 1), std::to_string(r.first_prefetch),
                           std::to_string(r.peak_objects)});
      bands.push_back({{"band", band}, {"route", run.name}, {"pbnp", result_json(r)}});
    }
    progress.update(++done);
  }
  progress.finish();

  const fs::path out(p.out_dir);
  fs::create_directories(out / "pvs-stream");
  for (int k = 0; k < 2; ++k) {
    LinePlot plot;
    plot.title = "Objects sent at each step, " + runs[k].name + " (Figure 7." + std::to_string(7 + k) + ")";
    plot.x_label = "step";
    plot.y_label = "objects sent";
    plot.series = {step_series("SNP", runs[k].snp), step_series("PBNP", runs[k].pbnp)};
    write_file_atomically((out / "pvs-stream" / ("route" + std::to_string(k + 1) + ".svg")).string(), render_svg(plot));
  }
  bench::write_csv(out / "pvs-stream" / "seeds.csv", seed_header, seed_rows);
  bench::write_csv(out / "pvs-stream" / "band.csv", band_header, band_rows);

  std::optional<PvsSocketBenchResult> net;
  if (p.sockets) net = run_pvs_socket_bench(p.net, out.string());

  const bool ordering = runs[0].pbnp.cache_swaps < runs[0].snp.cache_swaps && runs[1].pbnp.cache_swaps < runs[1].snp.cache_swaps;
  const double seconds = bench::seconds_since(start);
  std::string md = "# PVS streaming: SNP against PBNP (Zheng §7.5, Table 7.2)\n\n";
  md += "Generated by `" + p.command_line + "` on " + bench::utc_now() + " in " + fixed(seconds, 1) +
        " s; machine: " + machine.dump() + ".\n\n";
  md += "First a simulation, as the thesis's was (the walkthrough over sockets follows: \"Over sockets\"). The city: " +
        std::to_string(p.city.blocks) + " × " + std::to_string(p.city.blocks) + " buildings of " + fixed(p.city.building, 0) +
        " m, streets " + fixed(p.city.street, 0) + " m wide, " + fixed(p.city.cell, 0) + " m view cells: " +
        std::to_string(city.grid.view_cell_count()) + " view cells (the streets), " + std::to_string(city.table.objects) +
        " objects (one a building). The synthetic PVS table (seed " + std::to_string(p.city.seed) + "): each object is "
        "seen from rectangles of " + std::to_string(p.city.blob_min) + "–" + std::to_string(p.city.blob_max) +
        " cells a side about its building until " + fixed(100 * p.city.visible, 1) + " % of the view cells see it. "
        "Measured: a cell sees **" + fixed(100 * city.visible_fraction, 2) + " %** of the objects (thesis: about 5 %), "
        "adjacent cells share **" + fixed(100 * city.adjacent_overlap, 1) + " %** (thesis: about 60 %). Routes of " +
        std::to_string(p.route.steps) + " steps of " + fixed(p.route.step, 0) + " m; route 1 random (turns back with "
        "chance " + fixed(p.route.reverse_chance, 2) + " a step, turns at a crossing with chance " +
        fixed(p.route.turn_chance, 2) + "), route 2 a spiral of 7 straight pieces and 6 right turns. Both algorithms: "
        "a 9-row cache, delta transmission (ΔS = S_J − S_I), §7.4's replacement (rows with D_r > 1 or D_c > 1 go, "
        "the farthest first). PBNP's regions: bands " + fixed(p.band, 2) + " of a cell wide (the thesis gives none; "
        "swept below). \"Cache swaps\" counts the rows brought in (docs/pvs-stream.md says why).\n\n";
  md += "## Table 7.2\n\n" + table72(runs) + "\n";
  md += std::string("**Reading.** PBNP ") + (ordering ? "brings in fewer rows than SNP on both routes" : "does NOT bring in fewer rows than SNP on both routes") +
        " (route 1: " + std::to_string(runs[0].pbnp.cache_swaps) + " against " + std::to_string(runs[0].snp.cache_swaps) +
        "; route 2: " + std::to_string(runs[1].pbnp.cache_swaps) + " against " + std::to_string(runs[1].snp.cache_swaps) +
        "; the thesis: 876 against 1,785 and 828 against 1,797), sends fewer objects per transaction (" +
        fixed(runs[0].pbnp.objects_per_transaction(), 1) + " and " + fixed(runs[1].pbnp.objects_per_transaction(), 1) +
        " against " + fixed(runs[0].snp.objects_per_transaction(), 1) + " and " + fixed(runs[1].snp.objects_per_transaction(), 1) +
        "; thesis 16 against 30 and 29) and starts with less (" + std::to_string(runs[0].pbnp.first_prefetch) + " and " +
        std::to_string(runs[1].pbnp.first_prefetch) + " objects against " + std::to_string(runs[0].snp.first_prefetch) +
        " and " + std::to_string(runs[1].snp.first_prefetch) + ").\n\n";
  md += "## Route 1 with other seeds\n\n" + bench::md_table(seed_header, seed_rows, bench::Align::kFigures) + "\n";
  md += std::string("PBNP brings in fewer rows than SNP on ") + (pbnp_fewer_swaps_every_seed ? "every" : "NOT every") +
        " random route.\n\n";
  md += "## PBNP's region band\n\nA wider band prefetches earlier (more time for the data to arrive) and more often.\n\n" +
        bench::md_table(band_header, band_rows, bench::Align::kFigures) + "\n";
  md += "## Objects sent at each step (Figures 7.7, 7.8)\n\n![route 1](pvs-stream/route1.svg)\n\n![route 2](pvs-stream/route2.svg)\n\n";
  if (net) md += net->markdown;
  write_file_atomically((out / "pvs-stream.md").string(), md);

  Json routes = Json::array();
  for (const RouteRun& run : runs)
    routes.push_back({{"route", run.name}, {"snp", result_json(run.snp)}, {"pbnp", result_json(run.pbnp)}});
  return {{"view_cells", city.grid.view_cell_count()}, {"objects", city.table.objects},
          {"visible_fraction", city.visible_fraction}, {"adjacent_overlap", city.adjacent_overlap},
          {"routes", routes}, {"seeds", seeds}, {"bands", bands}, {"pbnp_fewer_swaps_both_routes", ordering},
          {"pbnp_fewer_swaps_every_seed", pbnp_fewer_swaps_every_seed},
          {"sockets", net ? net->json : Json(nullptr)}, {"clients", net ? net->clients : Json(nullptr)},
          {"sockets_pbnp_fewer_swaps", net ? Json(net->ordering_holds) : Json(nullptr)},
          {"sockets_target_met", net ? Json(net->target_met) : Json(nullptr)}, {"seconds", seconds}};
}

}  // namespace cellwalk
