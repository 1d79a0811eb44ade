// Zheng's PVS streaming (seed 004, ch. 7): the prefetching areas of SNP and PBNP (§7.2), the
// client cache against a brute-force oracle (§7.3, §7.4), and the simulation of §7.5.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "cellwalk/systems/pvs_stream/pvs_cache.hpp"
#include "cellwalk/systems/pvs_stream/pvs_prefetch.hpp"
#include "cellwalk/systems/pvs_stream/pvs_simulation.hpp"
#include "experiments/pvs_stream/pvs_stream_report.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using namespace pvs_stream;

ViewcellGrid full_grid(int n, double cell = 20.0) { return ViewcellGrid(n, n, cell, std::vector<uint8_t>(size_t(n) * n, 1)); }

std::set<GridCell> as_set(const std::vector<GridCell>& cells) { return {cells.begin(), cells.end()}; }

// Table 7.1, cell by cell: the current cell and the neighbours toward the region's side(s).
TEST(PvsPrefetch, PrefetchingAreaIsTable71) {
  const ViewcellGrid grid = full_grid(5);
  const GridCell c{2, 2};
  const GridCell n{1, 2}, s{3, 2}, e{2, 3}, w{2, 1}, nw{1, 1}, ne{1, 3}, se{3, 3}, sw{3, 1};
  const std::pair<Region, std::set<GridCell>> table[] = {
      {Region::M, {c}},          {Region::N, {c, n}},         {Region::S, {c, s}},
      {Region::E, {c, e}},       {Region::W, {c, w}},         {Region::NW, {c, n, w, nw}},
      {Region::NE, {c, n, e, ne}}, {Region::SE, {c, s, e, se}}, {Region::SW, {c, s, w, sw}}};
  for (const auto& [region, expected] : table) {
    const std::vector<GridCell> area = prefetching_area(PrefetchAlgorithm::pbnp, grid, c, region);
    EXPECT_EQ(as_set(area), expected) << region_name(region);
    EXPECT_EQ(area.front(), c);
    EXPECT_EQ(as_set(prefetching_area(PrefetchAlgorithm::snp, grid, c, region)).size(), 9u);  // SNP ignores regions
  }
  // Missing cells are never required: a corner of the grid, and a hole.
  std::vector<uint8_t> present(25, 1);
  present[grid.index(ne)] = 0;
  const ViewcellGrid holed(5, 5, 20.0, present);
  EXPECT_EQ(as_set(prefetching_area(PrefetchAlgorithm::pbnp, holed, c, Region::NE)), (std::set<GridCell>{c, n, e}));
  EXPECT_EQ(prefetching_area(PrefetchAlgorithm::snp, grid, GridCell{0, 0}, Region::M).size(), 4u);
}

TEST(PvsPrefetch, RegionsFollowTheBands) {
  const ViewcellGrid grid = full_grid(4);
  // Cell (1, 1) spans x, z in [20, 40); bands of a quarter: 5 m.
  EXPECT_EQ(grid.cell_at(25, 35), (GridCell{1, 1}));
  EXPECT_EQ(grid.region_at(30, 30, 0.25), Region::M);
  EXPECT_EQ(grid.region_at(30, 21, 0.25), Region::N);  // low z is north
  EXPECT_EQ(grid.region_at(30, 39, 0.25), Region::S);
  EXPECT_EQ(grid.region_at(39, 30, 0.25), Region::E);
  EXPECT_EQ(grid.region_at(21, 30, 0.25), Region::W);
  EXPECT_EQ(grid.region_at(21, 21, 0.25), Region::NW);
  EXPECT_EQ(grid.region_at(39, 39, 0.25), Region::SE);
  EXPECT_EQ(grid.region_at(30, 23, 0.1), Region::M);  // a narrower band
}

// §7.2's argument, checked everywhere: for any two regions side by side (across a region or a
// cell border) PBNP needs at most 4 cells, while SNP needs 12 (side) or 14 (corner) for two
// adjacent cells: more than the 9 entries, hence its oscillation.
TEST(PvsPrefetch, AdjacentRegionsNeedAtMostFourCellsSnpNeedsMoreThanNine) {
  const ViewcellGrid grid = full_grid(7);
  size_t most = 0;
  uint64_t pairs = 0;
  const double step = 0.5;  // m, finer than any band
  for (double x = 40.25; x < 100; x += step)
    for (double z = 40.25; z < 100; z += step)
      for (const auto& [dx, dz] : {std::pair{step, 0.0}, std::pair{0.0, step}, std::pair{step, step}}) {
        const GridCell a = grid.cell_at(x, z), b = grid.cell_at(x + dx, z + dz);
        const Region ra = grid.region_at(x, z, 0.25), rb = grid.region_at(x + dx, z + dz, 0.25);
        if (a == b && ra == rb) continue;
        std::set<GridCell> u = as_set(prefetching_area(PrefetchAlgorithm::pbnp, grid, a, ra));
        for (const GridCell& c : prefetching_area(PrefetchAlgorithm::pbnp, grid, b, rb)) u.insert(c);
        most = std::max(most, u.size());
        ++pairs;
      }
  EXPECT_GT(pairs, 1000u);
  EXPECT_EQ(most, 4u);
  const auto snp_union = [&](GridCell a, GridCell b) {
    std::set<GridCell> u = as_set(prefetching_area(PrefetchAlgorithm::snp, grid, a, Region::M));
    for (const GridCell& c : prefetching_area(PrefetchAlgorithm::snp, grid, b, Region::M)) u.insert(c);
    return u.size();
  };
  EXPECT_EQ(snp_union({3, 3}, {3, 4}), 12u);
  EXPECT_EQ(snp_union({3, 3}, {2, 4}), 14u);
}

// The cache against an oracle of sets, over random walks and random tables: ΔS = S_J − S_I, the
// database is the union of the cached rows, the area stays, at most `entries` rows, only
// non-neighbours go while there are any, and ΔS_d = S_d − S_c.
TEST(ClientPvsCache, MatchesTheSetOracle) {
  for (uint64_t seed : {1u, 2u, 3u, 4u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Random rng(seed);
    const int n = 9;
    std::vector<uint8_t> present(n * n);
    for (uint8_t& p : present) p = rng.chance(0.85);
    const ViewcellGrid grid(n, n, 10.0, present);
    PvsTable table;
    table.objects = 60;
    table.rows.resize(grid.cell_count());
    for (uint32_t i = 0; i < grid.cell_count(); ++i)
      if (grid.contains(grid.cell_of(i)))
        for (uint32_t id = 0; id < table.objects; ++id)
          if (rng.chance(0.15)) table.rows[i].push_back(id);
    const size_t entries = seed == 4 ? 5 : 9;
    ClientPvsCache cache(grid, table, entries);
    std::vector<GridCell> cached;  // the oracle's rows
    const auto row_union = [&](const std::vector<GridCell>& cells) {
      std::set<uint32_t> u;
      for (const GridCell& c : cells)
        for (uint32_t id : table.rows[grid.index(c)]) u.insert(id);
      return u;
    };
    uint64_t evicted_total = 0;
    for (int step = 0; step < 400; ++step) {
      GridCell current;
      do current = {int(rng.integer(0, n - 1)), int(rng.integer(0, n - 1))};
      while (!grid.contains(current));
      const Region region = Region(rng.integer(0, 8));
      const PrefetchAlgorithm algorithm =
          entries < 9 || rng.chance(0.5) ? PrefetchAlgorithm::pbnp : PrefetchAlgorithm::snp;
      const std::vector<GridCell> area = prefetching_area(algorithm, grid, current, region);
      const std::set<uint32_t> before = row_union(cached);
      const Transaction t = cache.update(current, area);
      std::vector<GridCell> requested;
      for (const GridCell& c : area)
        if (std::find(cached.begin(), cached.end(), c) == cached.end()) requested.push_back(c);
      ASSERT_EQ(as_set(t.requested), as_set(requested));
      std::set<uint32_t> delta;
      for (uint32_t id : row_union(requested))
        if (!before.count(id)) delta.insert(id);
      ASSERT_EQ(std::set<uint32_t>(t.delta.begin(), t.delta.end()), delta);
      // The rows after: before + requested − evicted; the area kept; the rule followed.
      std::vector<GridCell> all = cached;
      all.insert(all.end(), requested.begin(), requested.end());
      for (const GridCell& e : t.evicted) {
        ASSERT_TRUE(std::find(area.begin(), area.end(), e) == area.end());
        ASSERT_TRUE(std::find(all.begin(), all.end(), e) != all.end());
      }
      cached.clear();
      for (const GridCell& c : all)
        if (std::find(t.evicted.begin(), t.evicted.end(), c) == t.evicted.end()) cached.push_back(c);
      ASSERT_EQ(as_set(cache.cached_cells()), as_set(cached));
      ASSERT_LE(cached.size(), entries);
      ASSERT_EQ(t.evicted.size(), all.size() > entries ? all.size() - entries : 0u);
      for (const GridCell& c : area) ASSERT_TRUE(cache.cached(c));
      const bool evicted_a_neighbour = std::any_of(t.evicted.begin(), t.evicted.end(),
                                                   [&](GridCell e) { return chebyshev(e, current) <= 1; });
      const bool kept_a_stranger = std::any_of(cached.begin(), cached.end(),
                                               [&](GridCell c) { return chebyshev(c, current) > 1; });
      ASSERT_FALSE(evicted_a_neighbour && kept_a_stranger) << "a neighbour went while a non-neighbour stayed";
      const std::set<uint32_t> now = row_union(cached);
      ASSERT_EQ(std::set<uint32_t>(cache.objects().begin(), cache.objects().end()), now);
      std::set<uint32_t> dropped;
      for (uint32_t id : row_union(t.evicted))
        if (!now.count(id)) dropped.insert(id);
      ASSERT_EQ(std::set<uint32_t>(t.dropped.begin(), t.dropped.end()), dropped);
      evicted_total += t.evicted.size();
    }
    EXPECT_GT(evicted_total, 0u);  // the walk filled the cache
  }
}

// Back and forth across one border: PBNP across a region border fetches once (no oscillation);
// SNP across a cell border fetches at every crossing.
TEST(PvsSimulation, PbnpDoesNotOscillateSnpDoes) {
  SyntheticCityParams p;
  p.blocks = 4;
  const SyntheticCity city = make_synthetic_city(p);
  // Along the street at z = 30 (row 1, a street's middle row), x across the border at 100 m of
  // cells 4 and 5, whose bands (0.25 of 20 m) lie at [95, 100) and [100, 105).
  std::vector<Point2> route;
  for (int i = 0; i < 100; ++i) route.push_back({i % 2 ? 102.0 : 98.0, 30.0});
  const SimulationResult pbnp = simulate(city, route, PrefetchAlgorithm::pbnp, 0.25);
  const SimulationResult snp = simulate(city, route, PrefetchAlgorithm::snp, 0.25);
  EXPECT_LE(pbnp.transactions, 2u);
  EXPECT_GE(snp.transactions, 99u);  // a fetch at every crossing after the first
  EXPECT_EQ(snp.border_checks, 99u);
}

TEST(PvsSimulation, SyntheticCityHasTheThesisStatistics) {
  const SyntheticCity city = make_synthetic_city(SyntheticCityParams{});
  EXPECT_EQ(city.table.objects, 900u);
  EXPECT_EQ(city.grid.rows(), 243);  // 30 blocks of 160 m and one more street: 4,860 m
  EXPECT_EQ(city.grid.view_cell_count(), 243u * 243u - 900u * 25u);
  EXPECT_NEAR(city.visible_fraction, 0.05, 0.002);
  EXPECT_NEAR(city.adjacent_overlap, 0.6, 0.08);
  for (uint32_t i = 0; i < city.grid.cell_count(); ++i) {
    const std::vector<uint32_t>& row = city.table.rows[i];
    ASSERT_TRUE(std::is_sorted(row.begin(), row.end()));
    ASSERT_TRUE(std::adjacent_find(row.begin(), row.end()) == row.end());
    if (!city.grid.contains(city.grid.cell_of(i))) {
      ASSERT_TRUE(row.empty());
    }
  }
  EXPECT_THROW(make_synthetic_city(SyntheticCityParams{.blocks = 3, .building = 90}), Error);
}

TEST(PvsSimulation, RoutesWalkTheStreetsInSteps) {
  const SyntheticCity city = make_synthetic_city(SyntheticCityParams{.blocks = 12});
  for (uint64_t seed : {5u, 9u}) {
    const RouteParams rp{.steps = 1500, .seed = seed};
    for (const std::vector<Point2>& route : {random_route(city, rp), straight_route(city, rp)}) {
      ASSERT_EQ(route.size(), 1501u);
      int turns = 0;
      for (size_t i = 1; i < route.size(); ++i) {
        ASSERT_TRUE(city.grid.contains(city.grid.cell_at(route[i].x, route[i].z))) << "step " << i;
        ASSERT_NEAR(std::hypot(route[i].x - route[i - 1].x, route[i].z - route[i - 1].z), 4.0, 1e-9) << "step " << i;
        if (i >= 2) {
          const double cross = (route[i - 1].x - route[i - 2].x) * (route[i].z - route[i - 1].z) -
                               (route[i - 1].z - route[i - 2].z) * (route[i].x - route[i - 1].x);
          turns += std::abs(cross) > 1e-9;
        }
      }
      EXPECT_GT(turns, 0);
    }
  }
  // Route 2 of the thesis's city: 7 pieces, 6 right turns.
  const SyntheticCity thesis = make_synthetic_city(SyntheticCityParams{});
  const std::vector<Point2> route = straight_route(thesis, RouteParams{});
  int right_turns = 0;
  for (size_t i = 2; i < route.size(); ++i) {
    const double cross = (route[i - 1].x - route[i - 2].x) * (route[i].z - route[i - 1].z) -
                         (route[i - 1].z - route[i - 2].z) * (route[i].x - route[i - 1].x);
    right_turns += cross > 1e-9;  // x east, z south: a right turn has a positive cross product
    EXPECT_GE(cross, -1e-9) << "a left turn at step " << i;
  }
  EXPECT_EQ(right_turns, 6);
}

// Table 7.2's ordering on the thesis's city, for routes of seeds the thesis never saw: PBNP
// brings in fewer rows, sends fewer objects a transaction and starts with fewer objects; on the
// random route it needs fewer transactions too. (It may hold more objects at once: it replaces
// rows only when the 9 are full, SNP whenever it moves.)
TEST(PvsSimulation, PbnpBeatsSnpAsInTable72) {
  const SyntheticCity city = make_synthetic_city(SyntheticCityParams{.seed = 17});
  for (uint64_t seed : {7u, 11u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const RouteParams rp{.seed = seed};
    const std::vector<Point2> routes[2] = {random_route(city, rp), straight_route(city, rp)};
    for (int k = 0; k < 2; ++k) {
      const SimulationResult snp = simulate(city, routes[k], PrefetchAlgorithm::snp);
      const SimulationResult pbnp = simulate(city, routes[k], PrefetchAlgorithm::pbnp);
      EXPECT_LT(pbnp.cache_swaps, snp.cache_swaps) << "route " << k + 1;
      EXPECT_LT(pbnp.objects_per_transaction(), snp.objects_per_transaction()) << "route " << k + 1;
      EXPECT_LT(pbnp.first_prefetch, snp.first_prefetch) << "route " << k + 1;
      if (k == 0) {
        EXPECT_LT(pbnp.transactions, snp.transactions);
      }
      EXPECT_EQ(snp.objects_per_step.size(), routes[k].size());
    }
  }
}

TEST(PvsStreamBench, WritesItsReport) {
  const test::TempDir dir;
  PvsStreamBenchParams p;
  p.city.blocks = 6;
  p.route.steps = 400;
  p.seeds = {2};
  p.bands = {0.2, 0.4};
  p.out_dir = dir.path().string();
  // Over sockets, small: one path, one link, the two prefetchers.
  p.net.objects = 30;
  p.net.frames = 90;
  p.net.kinds = {"fast"};
  p.net.latencies = {20};
  p.net.bandwidths = {100};
  p.net.prefetchers = {"snp", "pbnp"};
  p.net.clients = 4;
  p.net.nginx_prefetchers = {"pbnp"};
  const nlohmann::ordered_json j = run_pvs_stream_bench(p);
  ASSERT_EQ(j["sockets"].size(), 3u);  // snp, pbnp, and pbnp from nginx
  EXPECT_EQ(j["sockets"][2]["server"], "nginx");
  for (const auto& run : j["sockets"]) {
    EXPECT_EQ(run["frames"].get<uint64_t>(), 90u);
    EXPECT_GT(run["transactions"].get<uint64_t>(), 0u);
    EXPECT_GT(run["bytes_received"].get<uint64_t>(), 0u);
    EXPECT_GE(run["startup_ms"].get<double>(), 40.0);  // a round trip over a 20 ms link
  }
  EXPECT_EQ(j["objects"].get<uint32_t>(), 36u);
  EXPECT_EQ(j["routes"].size(), 2u);
  EXPECT_EQ(j["bands"].size(), 4u);
  const std::string md(reinterpret_cast<const char*>(test::slurp(dir.file("pvs-stream.md")).data()),
                       test::slurp(dir.file("pvs-stream.md")).size());
  EXPECT_NE(md.find("Table 7.2"), std::string::npos);
  EXPECT_NE(md.find("1,785"), std::string::npos);  // the thesis's figures beside ours
  EXPECT_NE(md.find("## Over sockets"), std::string::npos);
  EXPECT_NE(md.find("| nginx"), std::string::npos);
  EXPECT_EQ(j["clients"]["clients"].get<int>(), 4);
  EXPECT_GT(j["clients"]["bytes"].get<uint64_t>(), 0u);
  EXPECT_GE(j["clients"]["p99_ms"].get<double>(), j["clients"]["p50_ms"].get<double>());
  EXPECT_GT(j["clients"]["peak_session_bytes"].get<uint64_t>(), 0u);
  for (const char* f : {"pvs-stream/route1.svg", "pvs-stream/route2.svg", "pvs-stream/band.csv", "pvs-stream/seeds.csv",
                        "pvs-stream/sockets.csv"})
    EXPECT_TRUE(std::filesystem::exists(dir.file(f))) << f;
  // Bad options: one line, a non-zero exit.
  for (const char* args : {"bench pvs-stream --band 0.6", "bench pvs-stream --blob-min 3 --blob-max 2", "bench pvs-stream --blocks 1",
                           "bench pvs-stream --prefetchers psychic", "bench pvs-stream --net-paths sideways",
                           "bench pvs-stream --nginx-prefetchers psychic"}) {
    const test::CommandResult r = test::run_cellwalk(std::string(args) + " --out " + dir.file("x"));
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
  }
}

}  // namespace
}  // namespace cellwalk
