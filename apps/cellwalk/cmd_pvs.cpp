// cellwalk pvs: precompute per-view-cell visible sets (and DoVs) into a world file, in shards
// and merged, or check an engine against the ground truth (docs/visibility.md).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/precompute/conservative_visibility.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "cellwalk/visibility/stored_vlod.hpp"
#include "checks.hpp"
#include "experiments/common/bench_support.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "precompute/dov_compare.hpp"
#include "precompute/ground_truth.hpp"
#include "precompute/embree_scene.hpp"
#include "precompute/ray_cube_map.hpp"
#include "precompute/pvs_builder.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

namespace {

struct Args {
  std::string world, out, engine = "sampling", cells = "grid:20", shard, dov_cubes = "rays", along;
  float along_margin = 0.0f;
  std::vector<std::string> merge;
  uint64_t check = 0, dov_compare = 0;
  int gt_points = 16, gt_resolution = 1024, threads = 0;
  std::string truth_cubes = "gl";
  EngineOptions options;
  double lod_height = 480, lod_fov = 60, lod_aspect = 4.0 / 3.0;
  bool faithful_bound = false;
  std::string disk_order = "tsp";
  bool disk_order_given = false;
  bool json = false;
  std::optional<uint64_t> show;  // --show CELL
  std::vector<double> at;        // --at X,Y,Z
};

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

nlohmann::ordered_json sizes_json(const visibility::PvsSizes& s) {
  return {{"cells", s.cells},
          {"cells_with_sets", s.cells_with_sets},
          {"ids", s.ids},
          {"bitmask_bytes", s.bitmask_bytes},
          {"gap_coded_bytes", s.full_bytes},
          {"stored_bytes", s.stored_bytes},
          {"delta_cells", s.delta_cells},
          {"face_pairs", s.face_pairs},
          {"face_delta_bytes", s.face_delta_bytes},
          {"dov_bytes", s.dov_bytes}};
}

void print_sizes(const visibility::PvsSizes& s) {
  std::printf("  %llu cells (%llu with sets), %.1f ids per set\n"
              "  stored %llu bytes (%llu as Δs) vs %llu gap-coded vs %llu as bitmasks (%.1fx smaller)\n"
              "  vLOD Δ per shared face: %.1f bytes over %llu pairs; dov %llu bytes\n",
              (unsigned long long)s.cells, (unsigned long long)s.cells_with_sets,
              double(s.ids) / double(std::max<uint64_t>(s.cells_with_sets, 1)), (unsigned long long)s.stored_bytes,
              (unsigned long long)s.delta_cells, (unsigned long long)s.full_bytes, (unsigned long long)s.bitmask_bytes,
              double(s.bitmask_bytes) / double(std::max<uint64_t>(s.stored_bytes, 1)),
              double(s.face_delta_bytes) / double(std::max<uint64_t>(s.face_pairs, 1)), (unsigned long long)s.face_pairs,
              (unsigned long long)s.dov_bytes);
}

// What the surface source found (--smallest-hole), or null when the engine has none.
nlohmann::ordered_json surface_json(const VisibilityEngine& engine) {
  const ConservativeStats* s = conservative_stats(engine);
  if (!s || s->voxel_edge <= 0.0) return nullptr;
  return {{"voxel_edge", s->voxel_edge}, {"voxels", s->voxels}, {"surface_voxels", s->surface_voxels},
          {"free_components", s->free_components}, {"boxes", s->surface_boxes}, {"setup_seconds", s->occluder_seconds}};
}

// The surface source's counts; or, when most objects are open and the source was not asked
// for, the option that would find occluders among them.
void print_surface(const VisibilityEngine& engine) {
  const ConservativeStats* s = conservative_stats(engine);
  if (s && s->voxel_edge <= 0.0 && s->closed_objects * 2 < s->objects)
    warn("pvs --engine conservative",
         std::to_string(s->closed_objects) + " of " + std::to_string(s->objects) +
             " objects are closed, and only closed ones give occluders; give --smallest-hole METRES to find occluders "
             "in the space the surfaces enclose together (docs/surface-occluders.md)");
  if (!s || s->voxel_edge <= 0.0) return;
  std::printf("  surface occluders: %.3f m voxels, %llu of %llu meet a surface, %llu free components, %llu boxes; "
              "occluders derived in %.1f s\n",
              s->voxel_edge, (unsigned long long)s->surface_voxels, (unsigned long long)s->voxels,
              (unsigned long long)s->free_components, (unsigned long long)s->surface_boxes, s->occluder_seconds);
}

void run_check(const Args& a, const World& world, const VisibilityEngine& engine,
               const ViewCellPartition& partition) {
  std::unique_ptr<visibility::CubeMapSource> cube;
  if (a.truth_cubes == "rays")
    cube = std::make_unique<visibility::RayCubeMap>(world, std::make_shared<const visibility::EmbreeScene>(world),
                                                    a.gt_resolution);
  else
    cube = std::make_unique<visibility::CubeMapRenderer>(world, a.gt_resolution);
  visibility::GroundTruthOptions gt;
  gt.points = a.gt_points;
  nlohmann::ordered_json cells = nlohmann::ordered_json::array();
  uint64_t found = 0, truth = 0, set = 0, failing = 0;
  double engine_s = 0, truth_s = 0, min_recall = 1.0;
  for (CellId c : visibility::cells_to_check(partition, a.check)) {
    const visibility::CellCheck r = visibility::check_cell(engine, *cube, partition.cell(c), gt);
    found += r.found;
    truth += r.truth_size;
    set += r.set_size;
    engine_s += r.engine_seconds;
    truth_s += r.truth_seconds;
    min_recall = std::min(min_recall, r.recall());
    failing += r.recall() < 1.0 ? 1 : 0;
    cells.push_back({{"cell", c}, {"set", r.set_size}, {"truth", r.truth_size}, {"recall", r.recall()},
                     {"tightness", r.tightness()}, {"missed", r.missed}, {"engine_seconds", r.engine_seconds},
                     {"truth_seconds", r.truth_seconds}});
    if (!a.json)
      std::printf("cell %6u: set %5llu truth %5llu recall %.4f tightness %.3f  %.3f s (truth %.1f s)\n", c,
                  (unsigned long long)r.set_size, (unsigned long long)r.truth_size, r.recall(), r.tightness(),
                  r.engine_seconds, r.truth_seconds);
  }
  const double n = double(std::max<size_t>(cells.size(), 1));
  const double recall = truth ? double(found) / double(truth) : 1.0;
  const double tightness = truth ? double(set) / double(truth) : 1.0;
  if (a.json) {
    nlohmann::ordered_json j = {{"engine", engine.name()}, {"conservative", engine.conservative()},
                                {"cells_spec", a.cells}, {"checked", cells.size()},
                                {"truth_points", a.gt_points + 8}, {"truth_resolution", a.gt_resolution},
                                {"truth_cubes", a.truth_cubes},
                                {"recall", recall}, {"min_recall", min_recall}, {"tightness", tightness},
                                {"cells_failing", failing}, {"engine_seconds_per_cell", engine_s / n},
                                {"truth_seconds_per_cell", truth_s / n}, {"checked_cells", cells}};
    if (const auto surface = surface_json(engine); !surface.is_null()) j["surface_occluders"] = surface;
    print_json("pvs", j);
  } else {
    print_surface(engine);
    std::printf("check %s: %zu cells, recall %.4f (min %.4f, %llu cells below 1), tightness %.3f, %.3f s per cell\n",
                engine.name().c_str(), cells.size(), recall, min_recall, (unsigned long long)failing, tightness,
                engine_s / n);
  }
  if (engine.conservative() && failing > 0)
    fail("pvs --check", "conservative engine '" + engine.name() + "' missed visible objects in " +
                            std::to_string(failing) + " cells");
}

void run_dov_compare(const Args& a, const World& world, const ViewCellPartition& partition) {
  const std::vector<CellId> cells = visibility::cells_to_check(partition, a.dov_compare);
  std::unique_ptr<Progress> progress;
  const visibility::DovComparison c =
      visibility::compare_dov_cubes(world, a.options, partition, cells, [&](uint64_t done, uint64_t total) {
        if (!progress) progress = std::make_unique<Progress>("dov exact vs " + a.dov_cubes, total);
        progress->update(done);
      });
  progress.reset();
  const double speedup = c.mode_cells_per_second() / c.exact_cells_per_second();
  const double engine_speedup = c.mode_engine_cells_per_second() / c.exact_engine_cells_per_second();
  if (a.json) {
    nlohmann::ordered_json j = {{"cells_spec", a.cells}, {"cells", c.cells}, {"resolution", c.resolution},
                                {"mode", a.dov_cubes}, {"exact_cells_per_second", c.exact_cells_per_second()},
                                {"mode_cells_per_second", c.mode_cells_per_second()}, {"speedup", speedup},
                                {"step1_seconds_per_cell", c.step1_seconds / double(c.cells)},
                                {"exact_engine_cells_per_second", c.exact_engine_cells_per_second()},
                                {"mode_engine_cells_per_second", c.mode_engine_cells_per_second()},
                                {"engine_speedup", engine_speedup}, {"max_dov_difference", c.max_difference},
                                {"largest_pixel_weight", c.largest_pixel_weight}, {"pairs", c.pairs},
                                {"one_sided", c.one_sided}, {"one_sided_max_dov", c.one_sided_max_dov}};
    print_json("pvs", j);
    return;
  }
  std::printf("dov cube maps at %d² on %llu %s cells, exact vs %s interleaved:\n"
              "  exact %.3f cells/s, %s %.3f cells/s: %.1fx\n"
              "  with step 1 (sampling, %.3f s/cell): exact %.3f cells/s, %s %.3f cells/s: %.1fx\n"
              "  max |DoV difference| %.3g (%.2f of the largest pixel weight %.3g); %llu of %llu (cell, object) pairs "
              "in one set only, largest DoV among them %.3g\n",
              c.resolution, (unsigned long long)c.cells, a.cells.c_str(), a.dov_cubes.c_str(), c.exact_cells_per_second(),
              a.dov_cubes.c_str(), c.mode_cells_per_second(), speedup, c.step1_seconds / double(c.cells),
              c.exact_engine_cells_per_second(), a.dov_cubes.c_str(), c.mode_engine_cells_per_second(), engine_speedup,
              c.max_difference, c.max_difference / c.largest_pixel_weight, c.largest_pixel_weight,
              (unsigned long long)c.one_sided, (unsigned long long)c.pairs, c.one_sided_max_dov);
}

nlohmann::ordered_json vlod_json(const visibility::VlodSizes& s) {
  nlohmann::ordered_json codecs;
  for (size_t i = 0; i < std::size(visibility::kIdCodecs); ++i)
    codecs[visibility::id_codec_name(visibility::kIdCodecs[i])] = s.codec_bytes[i];
  return {{"cells", s.cells},         {"cells_with_vlod", s.cells_with_vlod}, {"key_cells", s.keyframes},        {"face_pairs", s.face_pairs},
          {"delta_ids", s.delta_ids}, {"vlod_ids", s.vlod_ids},          {"bitmask_bytes", s.bitmask_bytes},
          {"list_bytes", s.list_bytes}, {"codec_bytes", codecs},         {"delta_bytes", s.delta_bytes},
          {"key_bytes", s.keyframe_bytes}, {"section_bytes", s.section_bytes},
          {"runs_world_order", s.runs_world_order}, {"runs_morton_order", s.runs_morton_order},
          {"runs_tsp_order", s.runs_tsp_order}, {"runs_written", s.runs_written}};
}

void print_vlod_sizes(const visibility::VlodSizes& s, const std::string& layout) {
  std::printf("  vlod section: %llu face Δs, %.1f ids each (%.1f%% of a vLOD), %llu key cells; Δs %llu bytes as stored "
              "(smallest codec per Δ) vs %llu as 32-bit ids vs %llu as bitmasks (%.0fx smaller)\n",
              (unsigned long long)s.face_pairs, double(s.delta_ids) / double(std::max<uint64_t>(s.face_pairs, 1)),
              100.0 * double(s.delta_ids) * double(std::max<uint64_t>(s.cells_with_vlod, 1)) /
                  double(std::max<uint64_t>(s.face_pairs, 1)) / double(std::max<uint64_t>(s.vlod_ids, 1)),
              (unsigned long long)s.keyframes, (unsigned long long)s.delta_bytes, (unsigned long long)s.list_bytes,
              (unsigned long long)s.bitmask_bytes, double(s.bitmask_bytes) / double(std::max<uint64_t>(s.delta_bytes, 1)));
  std::printf("   runs of added pieces R(M) (seed §3): world order %llu, Morton order %llu, Hamming-TSP order %llu "
              "(%.2fx fewer than the world's)\n",
              (unsigned long long)s.runs_world_order, (unsigned long long)s.runs_morton_order,
              (unsigned long long)s.runs_tsp_order,
              double(s.runs_world_order) / double(std::max<uint64_t>(s.runs_tsp_order, 1)));
  std::printf("   geometry laid out in the %s order: R(M) %llu\n", layout.c_str(), (unsigned long long)s.runs_written);
  std::printf("   one codec for every Δ:");
  for (size_t i = 0; i < std::size(visibility::kIdCodecs); ++i)
    std::printf(" %s %llu", visibility::id_codec_name(visibility::kIdCodecs[i]).c_str(), (unsigned long long)s.codec_bytes[i]);
  std::printf(" bytes\n");
}

// Writes the sets into `out`: a vlod run as the vlod section of per-face Δs and key cells (the
// world's other visible sets stay), any other run as the cells, pvs and dov sections.
visibility::PvsSizes write_sets(const Args& a, const World& world, const std::string& out, const ViewCellPartition& partition,
                                const visibility::CellSets& sets, const visibility::PvsRun& run,
                                std::optional<visibility::VlodSizes>& vlod) {
  const std::string prefix = "vlod:";
  if (run.engine.rfind(prefix, 0) != 0) {
    if (a.disk_order_given) fail("pvs --disk-order", "lays the geometry out for a vlod run only; give --engine vlod or leave it out");
    return visibility::write_world_with_pvs(world, out, partition, sets, run);
  }
  const visibility::CellLodRule rule = visibility::parse_cell_lod_rule(run.engine.substr(prefix.size()), "pvs run");
  vlod = visibility::write_world_with_vlod(world, out, partition, sets, rule, visibility::parse_disk_layout(a.disk_order));
  return {};
}

std::string point_text(double x, double y, double z) {
  return "(" + bench::fixed(x, 3) + ", " + bench::fixed(y, 3) + ", " + bench::fixed(z, 3) + ")";
}

// The cell --show or --at names, refused with what the world offers when there is none.
CellId cell_asked(const Args& a, const ViewCellPartition& partition) {
  if (a.show) {
    if (*a.show >= partition.cell_count())
      fail("pvs --show", "cell " + std::to_string(*a.show) + " does not exist: the world's " + partition.kind() +
                             " has cells 0 to " + std::to_string(partition.cell_count() - 1));
    return CellId(*a.show);
  }
  const Vec3 p(float(a.at[0]), float(a.at[1]), float(a.at[2]));
  const std::optional<CellId> cell = partition.locate(p);
  if (!cell) {
    Aabb extent;
    for (CellId c = 0; c < partition.cell_count(); ++c) extent.extend(partition.cell(c).box);
    fail("pvs --at", "the point " + point_text(a.at[0], a.at[1], a.at[2]) +
                         " lies in no view cell; the world's cells span " +
                         point_text(extent.min.x, extent.min.y, extent.min.z) + " to " +
                         point_text(extent.max.x, extent.max.y, extent.max.z));
  }
  return *cell;
}

// A name as one line of text: control characters as \xHH.
std::string printable(const std::string& name) {
  std::string out;
  for (const char c : name) {
    if (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f) {
      out += c;
      continue;
    }
    char hex[5];
    std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned char>(c));
    out += hex;
  }
  return out.empty() ? "(no name)" : out;
}

// pvs --show / --at: what the stored sets say about one cell, read back as every consumer reads
// them, so a user can check the engine's decision (issue 15).
void run_show(const Args& a, const World& world) {
  const std::string option = "pvs " + std::string(a.show ? "--show" : "--at");
  if (!world.file().has_section(visibility::kCellsSection)) {
    if (world.file().has_section(visibility::kVlodSection))
      fail(option, a.world + " holds vLOD sets only, which this does not read yet; compute plain sets beside them with cellwalk pvs " +
                       a.world + " --engine conservative");
    fail(option, a.world + " holds no visible sets yet; compute them first with cellwalk pvs " + a.world);
  }
  const visibility::StoredPvs pvs(world);
  const CellId id = cell_asked(a, pvs.partition());
  const ViewCell& cell = pvs.partition().cell(id);
  const char* state = cell.solid ? "solid" : cell.skipped ? "skipped" : "computed";
  const std::optional<VisibleSet> set = cell.computed() ? pvs.set(id) : std::nullopt;
  const std::vector<std::string> names = world.object_names();
  if (a.json) {
    nlohmann::ordered_json objects = nlohmann::ordered_json::array();
    if (set)
      for (size_t i = 0; i < set->objects.size(); ++i) {
        nlohmann::ordered_json o = {{"id", set->objects[i]}, {"name", names.at(set->objects[i])}};
        if (!set->dov.empty()) o["dov"] = set->dov[i];
        objects.push_back(o);
      }
    const nlohmann::ordered_json j = {{"cell", id},
                                      {"cells", pvs.partition().cell_count()},
                                      {"partition", pvs.partition().kind()},
                                      {"box", {{"min", {cell.box.min.x, cell.box.min.y, cell.box.min.z}},
                                               {"max", {cell.box.max.x, cell.box.max.y, cell.box.max.z}}}},
                                      {"depth", cell.depth},
                                      {"state", state},
                                      {"engine", pvs.engine()},
                                      {"conservative", pvs.conservative()},
                                      {"objects", objects}};
    print_json("pvs", j);
    return;
  }
  std::printf("cell %u of %zu (%s, depth %u): box (%.3f, %.3f, %.3f) to (%.3f, %.3f, %.3f), %s\n", id,
              pvs.partition().cell_count(), pvs.partition().kind().c_str(), cell.depth, cell.box.min.x, cell.box.min.y,
              cell.box.min.z, cell.box.max.x, cell.box.max.y, cell.box.max.z, state);
  if (!set) {
    std::printf("  no set: %s\n", cell.solid ? "the cell lies inside closed geometry, where no viewer can stand"
                                              : "pvs --along left it out; compute it with a pvs run that covers it");
    return;
  }
  std::printf("  engine %s (%s): %zu visible objects of %zu\n", pvs.engine().c_str(),
              pvs.conservative() ? "conservative" : "sampled", set->objects.size(), world.object_count());
  for (size_t i = 0; i < set->objects.size(); ++i) {
    const ObjectId o = set->objects[i];
    std::printf("  %8u  %s", o, printable(names.at(o)).c_str());
    if (!set->dov.empty()) std::printf("  dov %.3g", set->dov[i]);
    std::printf("\n");
  }
}

void run_merge(const Args& a, const World& world) {
  const std::string out = a.out.empty() ? a.world : a.out;
  refuse_same_files(a.merge, {out});
  const visibility::PvsMerge merged = visibility::merge_pvs_parts(a.merge, world);
  std::optional<visibility::VlodSizes> vlod;
  const visibility::PvsSizes sizes = write_sets(a, world, out, *merged.partition, merged.sets, merged.run, vlod);
  if (a.json) {
    nlohmann::ordered_json j = {{"output", out}, {"parts", a.merge.size()}};
    if (vlod) j["vlod"] = vlod_json(*vlod);
    else j["sizes"] = sizes_json(sizes);
    print_json("pvs", j);
    return;
  }
  std::printf("pvs: merged %zu parts into %s\n", a.merge.size(), out.c_str());
  if (vlod) print_vlod_sizes(*vlod, a.disk_order);
  else print_sizes(sizes);
}

// The cells spec's partition, restricted to the cells along the --along path when one is given.
// An octree for the vlod engine is refined by the triangles of its candidate cells' vLODs (§2.1).
std::unique_ptr<ViewCellPartition> cells_of_run(const Args& a, const World& world, const VisibilityEngine* engine = nullptr) {
  const visibility::EmbreeScene scene(world);
  const CellSetSize measure = engine && a.engine == "vlod" ? visibility::drawn_triangles(*engine, world, a.options.lod_rule)
                                                           : CellSetSize{};
  std::unique_ptr<ViewCellPartition> partition = visibility::make_partition(a.cells, world, scene, measure);
  if (a.along.empty()) return partition;
  const CameraPath path = read_path(a.along);
  warn_if_other_world(path, a.along, world.info(), a.world);
  return visibility::cells_along(*partition, path, a.along_margin);
}

void run_compute(const Args& a, const World& world) {
  if (a.dov_compare > 0) return run_dov_compare(a, world, *cells_of_run(a, world));
  auto setup = std::chrono::steady_clock::now();
  const std::unique_ptr<VisibilityEngine> engine = make_engine(a.engine, world, a.options);
  const std::unique_ptr<ViewCellPartition> partition = cells_of_run(a, world, engine.get());
  const double setup_s = seconds_since(setup);
  const visibility::PvsRun run = visibility::make_pvs_run(*engine, a.cells, a.options, a.shard, a.threads);
  if (a.check > 0) return run_check(a, world, *engine, *partition);
  const bool sharded = run.shards > 1;
  const std::string out = !a.out.empty() ? a.out
                          : sharded      ? a.world + ".part-" + std::to_string(run.shard) + "-of-" + std::to_string(run.shards)
                                         : a.world;
  const std::string checkpoint = sharded ? out : out + ".pvs-checkpoint";
  std::unique_ptr<Progress> progress;
  auto start = std::chrono::steady_clock::now();
  uint64_t resumed = 0;
  const visibility::CellSets sets =
      visibility::compute_cell_sets(world, *engine, *partition, run, checkpoint, [&](uint64_t done, uint64_t total) {
        if (!progress) {
          progress = std::make_unique<Progress>("pvs " + engine->name(), total);
          resumed = done;
        }
        progress->update(done);
      });
  const double compute_s = seconds_since(start);
  progress.reset();
  const uint64_t computed = sets.size() - resumed;
  visibility::PvsSizes sizes;
  std::optional<visibility::VlodSizes> vlod;
  if (!sharded) {
    sizes = write_sets(a, world, out, *partition, sets, run, vlod);
    std::filesystem::remove(checkpoint);
  }
  uint64_t solid = 0, skipped = 0;
  for (CellId c = 0; c < partition->cell_count(); ++c) {
    solid += partition->cell(c).solid ? 1 : 0;
    skipped += partition->cell(c).skipped ? 1 : 0;
  }
  const double rate = double(computed) / std::max(compute_s, 1e-9);
  if (a.json) {
    nlohmann::ordered_json j = {{"output", out}, {"engine", engine->name()}, {"cells_spec", a.cells},
                                {"partition", partition->kind()}, {"cells", partition->cell_count()},
                                {"solid_cells", solid}, {"skipped_cells", skipped}, {"shard", run.shard}, {"shards", run.shards},
                                {"computed", computed}, {"resumed", resumed}, {"setup_seconds", setup_s},
                                {"seconds", compute_s}, {"cells_per_second", rate}};
    if (vlod) j["vlod"] = vlod_json(*vlod);
    else if (!sharded) j["sizes"] = sizes_json(sizes);
    if (const auto surface = surface_json(*engine); !surface.is_null()) j["surface_occluders"] = surface;
    print_json("pvs", j);
    return;
  }
  std::printf("pvs %s: %zu %s cells (%llu solid, %llu skipped off the --along path); computed %llu (%llu resumed) in %.1f s, "
              "%.2f cells/s; setup %.1f s\n",
              engine->name().c_str(), partition->cell_count(), partition->kind().c_str(), (unsigned long long)solid,
              (unsigned long long)skipped, (unsigned long long)computed, (unsigned long long)resumed, compute_s, rate, setup_s);
  if (vlod) print_vlod_sizes(*vlod, a.disk_order);
  else if (!sharded) print_sizes(sizes);
  print_surface(*engine);
  std::printf("  wrote %s\n", out.c_str());
}

}  // namespace

void register_pvs(CLI::App& root) {
  auto* cmd = root.add_subcommand("pvs", "Precompute visible sets per view cell into a world file, or check an engine");
  auto a = std::make_shared<Args>();
  std::string engines;
  for (const std::string& n : engine_names()) engines += (engines.empty() ? "" : "|") + n;
  std::string dov_modes;
  for (const std::string& n : dov_cubes_names()) dov_modes += (dov_modes.empty() ? "" : "|") + n;
  cmd->add_option("world", a->world, "World file (.cww)")->required();
  std::vector<CLI::Option*> vlod_options;
  cmd->add_option("--engine", a->engine, "Visibility engine: " + engines)->capture_default_str();
  cmd->add_option("--cells", a->cells, "View cells: grid:SIZE | grid3d:SIZE | kd:SIZE | octree[:ROOT[:THRESHOLD[:DEPTH]]]")->capture_default_str();
  auto* along = cmd->add_option("--along", a->along, "Compute only the cells near this camera path (cellwalk path); the others are stored as skipped, and a walk entering one is refused");
  cmd->add_option("--along-margin", a->along_margin, "--along: metres around the path whose cells are computed")->capture_default_str()->check(number_in(0, 1e6))->needs(along);
  cmd->add_option("--shard", a->shard, "Compute only shard i of N equal cell-id ranges into a part file (i/N)");
  cmd->add_option("--merge", a->merge, "Merge the part files of every shard into the world")->expected(1, -1);
  cmd->add_option("-o,--output", a->out, "World to write (default: WORLD in place; WORLD.part-i-of-N for a shard)");
  cmd->add_option("--check", a->check, "Check the engine against ground truth on this many cells; write nothing")->check(integer_in(0, 1000000));
  cmd->add_option("--truth-points", a->gt_points, "Ground truth: random points per cell besides the 8 corners")->capture_default_str()->check(integer_in(0, 100000));
  cmd->add_option("--truth-resolution", a->gt_resolution, "Ground truth: cube-map face resolution")->capture_default_str()->check(integer_in(16, 4096));
  cmd->add_option("--truth-cubes", a->truth_cubes, "Ground truth: ID cube maps rasterised by GL (gl), or cast as Embree rays through the pixel centres (rays: no cracks where faces of different objects meet; docs/surface-occluders.md)")
      ->capture_default_str()
      ->check(CLI::IsMember({"gl", "rays"}));
  cmd->add_option("--points", a->options.sample_points, "Sampling: random points per cell")->capture_default_str()->check(integer_in(1, 100000));
  cmd->add_option("--rays", a->options.rays_per_point, "Sampling: rays per point")->capture_default_str()->check(integer_in(1, 10000000));
  cmd->add_option("--aimed-rays", a->options.aimed_rays_per_object, "Sampling: rays per point at each object's box")->capture_default_str()->check(integer_in(0, 10000));
  cmd->add_option("--refine", a->options.refine_levels, "Conservative: refinement levels of each cell for occluder shrinking")->capture_default_str()->check(integer_in(0, 8));
  auto* hole = cmd->add_option("--smallest-hole", a->options.smallest_hole, "Conservative: also find occluders in the space the surfaces enclose, keeping openings at least this wide open (metres; docs/surface-occluders.md)")->check(number_in(0, 1e6, true));
  cmd->add_option("--smallest-occluder", a->options.smallest_occluder, "--smallest-hole: drop occluder boxes thinner than this in their two longer edges (metres)")->capture_default_str()->check(number_in(0, 1e6))->needs(hole);
  vlod_options.push_back(cmd->add_option("--lod-height", a->lod_height, "vLOD: image height in pixels the levels are chosen for (a walk may use this or less)")->capture_default_str()->check(number_in(16, 8192)));
  vlod_options.push_back(cmd->add_option("--lod-fov", a->lod_fov, "vLOD: vertical field of view, degrees, the levels are chosen for")->capture_default_str()->check(number_in(1, 170)));
  vlod_options.push_back(cmd->add_option("--lod-aspect", a->lod_aspect, "vLOD: image width / height the levels are chosen for")->capture_default_str()->check(number_in(0.05, 20)));
  vlod_options.push_back(cmd->add_option("--pixel-error", a->options.lod_rule.pixel_error, "vLOD: the worst screen error of a level from anywhere in its cell, pixels")->capture_default_str()->check(number_in(0.01, 1000)));
  vlod_options.push_back(cmd->add_flag("--faithful-bound", a->faithful_bound, "vLOD: the seed's text of the per-cell bound (§2.2), not a bound; to reproduce the paper only"));
  CLI::Option* disk_order = cmd->add_option("--disk-order", a->disk_order, "vLOD: lay the geometry out on disk in this order of the pieces (§3): keep, morton or tsp")->capture_default_str()->check(CLI::IsMember(visibility::disk_layout_names()));
  cmd->add_option("--dov-resolution", a->options.dov_resolution, "DoV: cube-map face resolution")->capture_default_str()->check(integer_in(4, 4096));
  cmd->add_option("--dov-cubes", a->dov_cubes, "DoV: cube maps by " + dov_modes + " (exact: GL at level 0, the reference)")->capture_default_str();
  cmd->add_option("--dov-compare", a->dov_compare, "DoV: time exact against --dov-cubes on this many cells, interleaved, and print how far their DoVs differ; write nothing")->check(integer_in(0, 100000));
  cmd->add_flag("--dov-midpoint", a->options.dov_midpoint_weights, "DoV: eq. 5.11 at pixel centres, as the thesis writes it");
  cmd->add_option("--threads", a->threads, "Worker threads (0 = all cores)")->capture_default_str()->check(thread_count());
  cmd->add_flag("--json", a->json, "Print the report as JSON");
  auto* show = cmd->add_option("--show", a->show, "Print one cell's box and its stored visible objects (ids, names); compute nothing")
                   ->check(integer_in(0, int64_t(UINT32_MAX)));
  auto* at = cmd->add_option("--at", a->at, "Print the stored set of the cell holding the point X,Y,Z; compute nothing")
                 ->expected(3)
                 ->delimiter(',')
                 ->check(number_in(-1e30, 1e30));
  show->excludes(at);
  cmd->callback([cmd, a, vlod_options, disk_order, show, at, hole] {
    if (show->count() + at->count() > 0) {
      const std::string asked = show->count() > 0 ? "--show" : "--at";
      for (const CLI::Option* o : cmd->get_options())
        if (o->count() > 0 && o->nonpositional() && o != show && o != at && o->get_name() != "--json")
          fail("pvs " + asked, "reads the stored sets and computes nothing; leave out " + o->get_name());
      return run_show(*a, World(a->world));
    }
    a->disk_order_given = disk_order->count() > 0;
    if (a->disk_order_given && a->merge.empty() && a->engine != "vlod")
      fail("pvs --disk-order", "lays the geometry out for a vlod run only; give --engine vlod or leave it out");
    for (const CLI::Option* o : vlod_options)
      if (o->count() > 0 && a->engine != "vlod")
        fail("pvs " + o->get_name(), "chooses the levels of the vlod engine only; give --engine vlod or leave it out");
    if (hole->count() > 0 && a->engine != "conservative")
      fail("pvs --smallest-hole", "finds occluders for the conservative engine only (they hold at level 0); give --engine conservative");
    a->options.dov_cubes = parse_dov_cubes(a->dov_cubes);
    a->options.lod_rule.lens = Lens{float(a->lod_fov / 57.29577951308232), float(a->lod_aspect), float(a->lod_height)};
    if (a->faithful_bound) a->options.lod_rule.formula = CellBoundFormula::kFaithful;
    if (a->dov_compare > 0 && a->engine != "dov")
      fail("pvs --dov-compare", "compares the dov engine's cube-map modes; give --engine dov");
    const World world(a->world);
    if (!a->merge.empty()) return run_merge(*a, world);
    run_compute(*a, world);
  });
}

}  // namespace cellwalk::app
