// Seed 004 (Zheng), §7.5: the simulated city, its synthetic PVS table, the two routes and the
// walk that counts Table 7.2's figures.
#include "cellwalk/systems/pvs_stream/pvs_simulation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"

namespace cellwalk::pvs_stream {
namespace {

double period(const SyntheticCityParams& p) { return p.building + p.street; }

// Whether the coordinate lies in a street band (streets first: [k·period, k·period + street)).
bool in_street(const SyntheticCityParams& p, double v) {
  const double m = v - std::floor(v / period(p)) * period(p);
  return m < p.street;
}

double extent(const SyntheticCityParams& p) { return p.blocks * period(p) + p.street; }

bool is_multiple(double value, double of) { return std::abs(value / of - std::round(value / of)) < 1e-9; }

double normal(Random& rng) {
  const double u = std::max(rng.uniform(), 1e-300);
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * rng.uniform());
}

ViewcellGrid street_grid(const SyntheticCityParams& p) {
  const int n = int(std::lround(extent(p) / p.cell));
  std::vector<uint8_t> present(size_t(n) * size_t(n));
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      present[size_t(r) * size_t(n) + size_t(c)] = in_street(p, (r + 0.5) * p.cell) || in_street(p, (c + 0.5) * p.cell);
  return ViewcellGrid(n, n, p.cell, std::move(present));
}

// Object `id`'s visible cells: rectangles about its building until `target` view cells see it.
void add_object(const SyntheticCity& city, uint32_t id, uint32_t target, Random rng, std::vector<uint32_t>& stamp,
                std::vector<std::vector<uint32_t>>& rows) {
  const SyntheticCityParams& p = city.params;
  const double cx = (id % uint32_t(p.blocks)) * period(p) + p.street + p.building / 2;
  const double cz = (id / uint32_t(p.blocks)) * period(p) + p.street + p.building / 2;
  uint32_t seen = 0;
  for (uint64_t tries = 0; seen < target && tries < 1000ull * target; ++tries) {
    const GridCell centre = city.grid.cell_at(cx + p.spread * normal(rng), cz + p.spread * normal(rng));
    const int w = int(rng.integer(p.blob_min, p.blob_max)), h = int(rng.integer(p.blob_min, p.blob_max));
    for (int r = centre.row - h / 2; r < centre.row - h / 2 + h && seen < target; ++r)
      for (int c = centre.col - w / 2; c < centre.col - w / 2 + w && seen < target; ++c) {
        const GridCell cell{r, c};
        if (!city.grid.contains(cell) || stamp[city.grid.index(cell)] == id + 1) continue;
        stamp[city.grid.index(cell)] = id + 1;
        rows[city.grid.index(cell)].push_back(id);
        ++seen;
      }
  }
}

void measure(SyntheticCity& city) {
  const ViewcellGrid& g = city.grid;
  double fraction = 0, overlap = 0;
  uint64_t cells = 0, pairs = 0;
  for (uint32_t i = 0; i < g.cell_count(); ++i) {
    const GridCell a = g.cell_of(i);
    if (!g.contains(a)) continue;
    const std::vector<uint32_t>& si = city.table.rows[i];
    fraction += double(si.size()) / city.table.objects;
    ++cells;
    if (si.empty()) continue;
    for (const GridCell b : {GridCell{a.row - 1, a.col}, GridCell{a.row + 1, a.col}, GridCell{a.row, a.col - 1},
                             GridCell{a.row, a.col + 1}}) {
      if (!g.contains(b)) continue;
      const std::vector<uint32_t>& sj = city.table.rows[g.index(b)];
      overlap += double(si.size() - minus(si, sj).size()) / double(si.size());
      ++pairs;
    }
  }
  city.visible_fraction = cells ? fraction / double(cells) : 0.0;
  city.adjacent_overlap = pairs ? overlap / double(pairs) : 0.0;
}

}  // namespace

SyntheticCity make_synthetic_city(const SyntheticCityParams& p) {
  if (p.blocks < 2 || p.blocks > 1000 || !(p.cell > 0) || !is_multiple(p.building, p.cell) || !is_multiple(p.street, p.cell) ||
      !(p.building > 0) || !(p.street > 0))
    throw Error("synthetic city: " + std::to_string(p.blocks) + " blocks with buildings of " + std::to_string(p.building) +
                " m and streets of " + std::to_string(p.street) + " m need 2..1000 blocks and sides that are whole numbers of " +
                std::to_string(p.cell) + " m cells");
  if (!(p.visible > 0 && p.visible <= 1) || p.blob_min < 1 || p.blob_max < p.blob_min || !(p.spread >= 0))
    throw Error("synthetic city: the visible fraction must be in (0, 1], the blob sides 1 <= min <= max, the spread >= 0");
  SyntheticCity city{p, street_grid(p), PvsTable{}, 0.0, 0.0};
  city.table.objects = uint32_t(p.blocks) * uint32_t(p.blocks);
  city.table.rows.resize(city.grid.cell_count());
  const uint32_t target = std::max<uint32_t>(1, uint32_t(std::lround(p.visible * city.grid.view_cell_count())));
  std::vector<uint32_t> stamp(city.grid.cell_count(), 0);
  Random rng(p.seed);
  for (uint32_t id = 0; id < city.table.objects; ++id) add_object(city, id, target, rng.split(id), stamp, city.table.rows);
  measure(city);
  return city;
}

namespace {

struct Heading {
  int dx = 1, dz = 0;
};

bool walkable(const SyntheticCity& city, double x, double z) {
  const double e = extent(city.params);
  return x > 0 && z > 0 && x < e && z < e && city.grid.contains(city.grid.cell_at(x, z));
}

bool at_crossing(const SyntheticCityParams& p, double x, double z) { return in_street(p, x) && in_street(p, z); }

}  // namespace

std::vector<Point2> random_route(const SyntheticCity& city, const RouteParams& params) {
  const SyntheticCityParams& p = city.params;
  Random rng(params.seed);
  // Start at a random crossing, on a random lane.
  const auto line = [&](int64_t k) { return double(k) * period(p) + p.street / 2; };
  Point2 at{line(rng.integer(1, p.blocks - 1)), line(rng.integer(1, p.blocks - 1))};
  at.x += rng.uniform(-0.4, 0.4) * p.street;
  at.z += rng.uniform(-0.4, 0.4) * p.street;
  const Heading kHeadings[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  Heading h = kHeadings[rng.integer(0, 3)];
  std::vector<Point2> route{at};
  bool was_crossing = true;
  for (int s = 0; s < params.steps; ++s) {
    if (rng.chance(params.reverse_chance)) h = {-h.dx, -h.dz};
    const bool crossing = at_crossing(p, at.x, at.z);
    if (crossing && !was_crossing && rng.chance(params.turn_chance))
      h = rng.chance(0.5) ? Heading{h.dz, h.dx} : Heading{-h.dz, -h.dx};
    was_crossing = crossing;
    // Blocked (a building or the city's edge): another heading, the perpendiculars first.
    for (const Heading& next : {h, Heading{h.dz, h.dx}, Heading{-h.dz, -h.dx}, Heading{-h.dx, -h.dz}})
      if (walkable(city, at.x + next.dx * params.step, at.z + next.dz * params.step)) {
        h = next;
        break;
      }
    at = {at.x + h.dx * params.step, at.z + h.dz * params.step};
    route.push_back(at);
  }
  return route;
}

std::vector<Point2> straight_route(const SyntheticCity& city, const RouteParams& params) {
  const SyntheticCityParams& p = city.params;
  // The thesis's seven pieces in proportion (in blocks, for 30 blocks and 12 km: 16, 15, 14, 10,
  // 9, 6, 5), a spiral inwards of right turns: east, south, west, north, east, south, west. A city
  // too small for them gets more pieces, each to the edge, until the steps are spent.
  const double weights[7] = {16, 15, 14, 10, 9, 6, 5};
  const Heading kCycle[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  const double total_blocks = params.steps * params.step / period(p);
  const auto line = [&](int k) { return k * period(p) + p.street / 2; };
  int line_x = 1, line_z = 1;  // street centre lines, 0..blocks
  std::vector<Point2> route{{line(line_x), line(line_z)}};
  for (int piece = 0, stuck = 0; int(route.size()) <= params.steps && stuck < 4; ++piece) {
    const Heading h = kCycle[piece % 4];
    const int limit = h.dx > 0 ? p.blocks - line_x : h.dx < 0 ? line_x : h.dz > 0 ? p.blocks - line_z : line_z;
    int blocks = piece < 6 ? std::max(1, int(std::lround(weights[piece] / 75.0 * total_blocks))) : limit;
    blocks = std::min(blocks, limit);  // stay within the city's outer street lines
    stuck = blocks == 0 ? stuck + 1 : 0;
    const int steps_per_block = int(std::lround(period(p) / params.step));
    for (int s = 0; s < blocks * steps_per_block && int(route.size()) <= params.steps; ++s) {
      const Point2& last = route.back();
      route.push_back({last.x + h.dx * params.step, last.z + h.dz * params.step});
    }
    line_x += h.dx * blocks;
    line_z += h.dz * blocks;
  }
  return route;
}

SimulationResult simulate(const SyntheticCity& city, const std::vector<Point2>& route, PrefetchAlgorithm algorithm,
                          double band, size_t entries) {
  if (!(band > 0 && band < 0.5)) throw Error("PVS simulation: the region band must be in (0, 0.5) of a cell");
  ClientPvsCache cache(city.grid, city.table, entries);
  SimulationResult result;
  GridCell last_cell{-1, -1};
  Region last_region = Region::M;
  for (size_t i = 0; i < route.size(); ++i) {
    const GridCell cell = city.grid.cell_at(route[i].x, route[i].z);
    if (!city.grid.contains(cell))
      throw Error("PVS simulation: position " + std::to_string(i) + " of the route lies in no view cell");
    const Region region = city.grid.region_at(route[i].x, route[i].z, band);
    const bool crossed = cell != last_cell || (algorithm == PrefetchAlgorithm::pbnp && region != last_region);
    uint32_t sent = 0;
    if (crossed) {
      if (i > 0) ++result.border_checks;
      const Transaction t = cache.update(cell, prefetching_area(algorithm, city.grid, cell, region));
      if (!t.requested.empty()) {
        if (result.transactions == 0) result.first_prefetch = t.delta.size();
        ++result.transactions;
        result.cache_swaps += t.requested.size();
        result.evictions += t.evicted.size();
        result.objects_sent += t.delta.size();
        sent = uint32_t(t.delta.size());
      }
      // The database is the union of the cached rows (§7.4's consistency), the viewpoint's among them.
      std::vector<const std::vector<uint32_t>*> rows;
      for (const GridCell& c : cache.cached_cells()) rows.push_back(&city.table.rows[city.grid.index(c)]);
      if (!cache.cached(cell) || union_of(rows) != cache.objects() || cache.cached_cells().size() > entries)
        throw Error("PVS simulation: the client cache lost its consistency at position " + std::to_string(i));
      result.peak_objects = std::max<uint64_t>(result.peak_objects, cache.objects().size());
    }
    result.objects_per_step.push_back(sent);
    last_cell = cell;
    last_region = region;
  }
  return result;
}

}  // namespace cellwalk::pvs_stream
