// Per-cell visible sets for a whole world: parallel (TBB), resumable checkpoints, shards and
// merging, and the "cells"/"pvs"/"dov" sections. vLOD §2.3–§2.4 (Δs between face neighbours,
// digest 001 §3.3–§3.4); HDoV thesis §5.5 (per-cell DoV, digest 000 §3.9).
#include "precompute/pvs_builder.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <xxhash.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <optional>

#include "cellwalk/core/error.hpp"
#include "core/bytes.hpp"
#include "store/checkpoint_file.hpp"
#include "precompute/sampling_engine.hpp"
#include "visibility/set_codec.hpp"

namespace cellwalk::visibility {

namespace {

constexpr char kPartMagic[8] = {'C', 'W', 'P', 'V', 'S', 'C', 'K', '1'};

float parse_float(const std::string& spec, const std::string& text) {
  try {
    size_t used = 0;
    const float v = std::stof(text, &used);
    if (used == text.size() && v > 0.0f && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  fail("cells spec '" + spec + "'", "'" + text + "' is not a finite positive number");
}

std::vector<std::string> split_colons(const std::string& s) {
  std::vector<std::string> parts;
  size_t start = 0;
  for (size_t i = 0; i <= s.size(); ++i)
    if (i == s.size() || s[i] == ':') {
      parts.push_back(s.substr(start, i - start));
      start = i + 1;
    }
  return parts;
}

// The octree's set size: level-0 triangles of what a light sampling engine sees (vLOD counts
// triangles of the visible set).
CellSetSize sampled_triangles(const World& world) {
  EngineOptions light;
  light.sample_points = 4;
  light.rays_per_point = 1024;
  auto engine = std::make_shared<SamplingEngine>(world, light);
  return [engine, &world](const Aabb& box) {
    uint64_t triangles = 0;
    for (ObjectId id : engine->compute(ViewCell{0, box, 0, false}).objects) triangles += world.lod(id, 0).triangles;
    return triangles;
  };
}

uint64_t run_hash(const World& world, const PvsRun& run, std::span<const uint8_t> cells) {
  ByteWriter w;
  w.put_string(run.engine);
  w.put_string(run.settings);
  w.put(run.shard);
  w.put(run.shards);
  w.put(uint64_t(world.object_count()));
  const std::vector<uint8_t> objects = world.file().read_all("objects");
  w.put(XXH3_64bits(objects.data(), objects.size()));
  w.put(XXH3_64bits(cells.data(), cells.size()));
  return XXH3_64bits(w.bytes().data(), w.size());
}

std::vector<uint8_t> part_header(const PvsRun& run, uint64_t hash, std::span<const uint8_t> cells) {
  ByteWriter w;
  w.put_array(std::span<const char>(kPartMagic, 8));
  w.put(hash);
  w.put(uint32_t(run.shard));
  w.put(uint32_t(run.shards));
  w.put_string(run.engine);
  w.put(uint8_t(run.conservative));
  w.put_string(run.settings);
  w.put(uint32_t(cells.size()));
  w.put_array(cells);
  w.put(XXH3_64bits(w.bytes().data(), w.size()));
  return std::move(w.bytes());
}

std::vector<uint8_t> encode_record(CellId cell, const VisibleSet& set) {
  std::vector<uint8_t> payload;
  put_varint(payload, cell);
  append_set(payload, set.objects);
  payload.push_back(set.dov.empty() ? 0 : 1);
  const auto* dov = reinterpret_cast<const uint8_t*>(set.dov.data());
  payload.insert(payload.end(), dov, dov + set.dov.size() * sizeof(float));
  std::vector<uint8_t> record;
  append_framed_record(record, payload);
  return record;
}

// A part or checkpoint file as read: its header fields, the sets of its intact records, and
// where the intact part ends (a killed writer may leave a torn last record).
struct ParsedPart {
  uint64_t hash = 0;
  PvsRun run;
  std::vector<uint8_t> cells;
  CellSets sets;
  uint64_t valid_bytes = 0;
};

// The header; throws Error when it is truncated or damaged. Leaves `r` at the first record.
ParsedPart parse_header(ByteReader& r, std::span<const uint8_t> bytes) {
  ParsedPart p;
  if (r.get_array<char>(8, "magic") != std::vector<char>(kPartMagic, kPartMagic + 8))
    r.error("not a cellwalk pvs part or checkpoint (bad magic)");
  p.hash = r.get<uint64_t>("run hash");
  p.run.shard = int(r.get<uint32_t>("shard"));
  p.run.shards = int(r.get<uint32_t>("shards"));
  p.run.engine = r.get_string("engine");
  p.run.conservative = r.get<uint8_t>("conservative") != 0;
  p.run.settings = r.get_string("settings");
  p.cells = r.get_array<uint8_t>(r.get<uint32_t>("cells length"), "cells");
  const uint64_t header_end = r.offset();
  if (r.get<uint64_t>("header checksum") != XXH3_64bits(bytes.data(), header_end)) r.error("header checksum mismatch");
  p.valid_bytes = r.offset();
  return p;
}

// Records until the first torn or damaged one: everything after it is recomputed.
void parse_records(ByteReader& r, const std::string& path, uint64_t object_count, ParsedPart& p) {
  while (const std::optional<std::vector<uint8_t>> record = next_framed_record(r)) {
    const std::vector<uint8_t>& payload = *record;
    size_t pos = 0;
    const CellId cell = CellId(get_varint(payload, pos, path));
    VisibleSet set;
    set.objects = read_set(payload, pos, path, object_count);
    if (pos < payload.size() && payload[pos++] == 1) {
      if ((payload.size() - pos) != set.objects.size() * sizeof(float)) fail(path, "record DoV length mismatch");
      set.dov.resize(set.objects.size());
      std::memcpy(set.dov.data(), payload.data() + pos, payload.size() - pos);
    }
    p.sets[cell] = std::move(set);
    p.valid_bytes = r.offset();
  }
}

ParsedPart parse_part(const std::string& path, uint64_t object_count) {
  const std::vector<uint8_t> bytes = read_checkpoint_file(path);
  ByteReader r(bytes, path);
  ParsedPart p = parse_header(r, bytes);
  parse_records(r, path, object_count, p);
  return p;
}

// What a checkpoint lets a run reuse: nothing when there is none, or when its header is
// truncated or damaged (a disk that filled while it was created, a damaged file): its records
// cannot be trusted to belong to this run, so it is discarded with a warning and the run starts
// over rather than failing every later run. An intact header of another run is an Error: that
// checkpoint may be worth keeping, and only the user knows.
ParsedPart resumable_part(const std::string& checkpoint, uint64_t hash, uint64_t object_count) {
  if (!std::filesystem::exists(checkpoint)) return {};
  const std::vector<uint8_t> bytes = read_checkpoint_file(checkpoint);
  ByteReader r(bytes, checkpoint);
  ParsedPart p;
  try {
    p = parse_header(r, bytes);
  } catch (const Error& e) {
    warn(e.what(), "the checkpoint's header is unreadable, so it is discarded and every cell is computed again");
    return {};
  }
  if (p.hash != hash)
    fail(checkpoint, "belongs to a different run (world, cells, engine, settings or shard); delete it to start over");
  parse_records(r, checkpoint, object_count, p);
  return p;
}

}  // namespace

// "i/N" exactly: two whole numbers, 0 <= i < N, nothing before or after.
void parse_shard(const std::string& text, int& shard, int& shards) {
  const size_t slash = text.find('/');
  const auto whole = [&](size_t from, size_t to, int& out) {
    const auto [stop, error] = std::from_chars(text.data() + from, text.data() + to, out);
    return from < to && error == std::errc() && stop == text.data() + to;
  };
  if (slash == std::string::npos || !whole(0, slash, shard) || !whole(slash + 1, text.size(), shards) ||
      shards < 1 || shard < 0 || shard >= shards)
    fail("--shard '" + text + "'", "expected i/N with 0 <= i < N, e.g. 0/4");
}


CellSetSize drawn_triangles(const VisibilityEngine& engine, const World& world, const CellLodRule& rule) {
  return [&engine, &world, rule](const Aabb& box) {
    uint64_t triangles = 0;
    for (ObjectId id : engine.compute(ViewCell{0, box, 0, false}).objects)
      triangles += world.lod(id, cell_level(world, id, box, rule)).triangles;
    return triangles;
  };
}

std::unique_ptr<ViewCellPartition> make_partition(const std::string& spec, const World& world,
                                                  const EmbreeScene& scene, const CellSetSize& set_size) {
  const std::vector<std::string> parts = split_colons(spec);
  const std::string& kind = parts[0];
  const SolidTest solid = [&scene](const Aabb& box) { return scene.box_is_solid(box); };
  const bool three_d = kind == "grid3d";
  const CellRegion region = default_cell_region(world.info().bounds, world.info().nav, !three_d);
  if ((kind == "grid" || kind == "grid3d" || kind == "kd") && parts.size() == 2) {
    const float size = parse_float(spec, parts[1]);
    return kind == "kd" ? make_kd_partition(region, size, solid) : make_grid_partition(region, size, solid);
  }
  if (kind == "octree" && parts.size() <= 4) {
    OctreeRules rules;
    if (parts.size() > 1) rules.root_size = parse_float(spec, parts[1]);
    // Checked as floats: casting one beyond the integer's range is undefined.
    const float threshold = parts.size() > 2 ? parse_float(spec, parts[2]) : float(rules.threshold);
    const float depth = parts.size() > 3 ? parse_float(spec, parts[3]) : float(rules.max_depth);
    if (threshold > 1e15f) fail("cells spec '" + spec + "'", "octree threshold must be at most 1e15 triangles; give a smaller THRESHOLD");
    if (depth > 10.0f)  // 8^10 leaves per root: far beyond what a run can compute
      fail("cells spec '" + spec + "'", "octree depth must be at most 10; give a smaller DEPTH");
    rules.threshold = uint64_t(threshold);
    rules.max_depth = uint32_t(depth);
    return make_octree_partition(region, rules, set_size ? set_size : sampled_triangles(world), solid);
  }
  fail("cells spec '" + spec + "'", "expected grid:SIZE, grid3d:SIZE, kd:SIZE or octree[:ROOT[:THRESHOLD[:DEPTH]]]");
}

namespace {

// Whether the segment a→b meets `box` (slab test; a degenerate segment is its point).
bool segment_meets_box(const Vec3& a, const Vec3& b, const Aabb& box) {
  double t0 = 0.0, t1 = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double from = a[axis], d = double(b[axis]) - from;
    if (d == 0.0) {
      if (from < box.min[axis] || from > box.max[axis]) return false;
      continue;
    }
    double lo = (box.min[axis] - from) / d, hi = (box.max[axis] - from) / d;
    if (lo > hi) std::swap(lo, hi);
    t0 = std::max(t0, lo);
    t1 = std::min(t1, hi);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

std::unique_ptr<ViewCellPartition> cells_along(const ViewCellPartition& partition, const CameraPath& path, float margin) {
  if (path.frames.empty()) fail("--along", "the path has no frames; give a path made by `cellwalk path`");
  if (!(margin >= 0.0f) || !std::isfinite(margin))
    fail("--along-margin", std::to_string(margin) + " must be a finite number of metres >= 0");
  Aabb reach;  // the path's box: most cells of a large partition are far from all of it
  for (const PathFrame& f : path.frames) reach.extend(f.position);
  return skip_cells(partition, [&](const ViewCell& cell) {
    const Aabb grown{cell.box.min - Vec3(margin), cell.box.max + Vec3(margin)};
    if (!grown.overlaps(reach)) return false;
    for (size_t i = 0; i < path.frames.size(); ++i)
      if (segment_meets_box(path.frames[i].position, path.frames[i + 1 < path.frames.size() ? i + 1 : i].position, grown))
        return true;
    return false;
  });
}

PvsRun make_pvs_run(const VisibilityEngine& engine, const std::string& cells_spec, const EngineOptions& o,
                    const std::string& shard, int threads) {
  PvsRun run;
  run.engine = engine.name();
  run.conservative = engine.conservative();
  run.settings = cells_spec + " points=" + std::to_string(o.sample_points) + " rays=" + std::to_string(o.rays_per_point) +
                 " aimed=" + std::to_string(o.aimed_rays_per_object) + " seed=" + std::to_string(o.seed) +
                 " dov=" + std::to_string(o.dov_resolution) + " cubes=" + dov_cubes_name(o.dov_cubes) +
                 (run.conservative ? " refine=" + std::to_string(o.refine_levels) : "") +
                 (o.smallest_hole > 0.0 ? " hole=" + std::to_string(o.smallest_hole) +
                                              " occluder=" + std::to_string(o.smallest_occluder)
                                        : "") +
                 (o.dov_midpoint_weights ? " midpoint" : "");
  run.threads = threads;
  if (!shard.empty()) parse_shard(shard, run.shard, run.shards);
  return run;
}

std::vector<CellId> shard_cells(const ViewCellPartition& partition, int shard, int shards) {
  if (shards < 1 || shard < 0 || shard >= shards) fail("--shard", "expected i/N with 0 <= i < N");
  const uint64_t n = partition.cell_count();
  std::vector<CellId> out;
  for (uint64_t c = n * uint64_t(shard) / uint64_t(shards); c < n * uint64_t(shard + 1) / uint64_t(shards); ++c)
    if (partition.cell(CellId(c)).computed()) out.push_back(CellId(c));
  return out;
}

CellSets compute_cell_sets(const World& world, const VisibilityEngine& engine,
                           const ViewCellPartition& partition, const PvsRun& run,
                           const std::string& checkpoint,
                           const std::function<void(uint64_t, uint64_t)>& progress) {
  const std::vector<uint8_t> cells = serialize_partition(partition);
  const uint64_t hash = run_hash(world, run, cells);
  ParsedPart old = resumable_part(checkpoint, hash, world.object_count());
  CellSets sets = std::move(old.sets);
  const uint64_t keep = old.valid_bytes;
  const std::vector<CellId> all = shard_cells(partition, run.shard, run.shards);
  std::vector<CellId> todo;
  for (CellId c : all)
    if (!sets.count(c)) todo.push_back(c);
  CheckpointWriter out(checkpoint, keep, part_header(run, hash, cells));
  std::mutex mutex;
  uint64_t done = all.size() - todo.size();
  if (progress) progress(done, all.size());
  tbb::task_arena arena(run.threads > 0 ? run.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(size_t(0), todo.size(), size_t(1), [&](size_t i) {
      VisibleSet set = engine.compute(partition.cell(todo[i]));
      const std::vector<uint8_t> record = encode_record(todo[i], set);
      std::lock_guard lock(mutex);
      out.write_all(record);
      sets[todo[i]] = std::move(set);
      if (progress) progress(++done, all.size());
    });
  });
  return sets;
}

PvsPart read_pvs_part(const std::string& path, const World& world) {
  ParsedPart p = parse_part(path, world.object_count());
  PvsPart part;
  part.partition = deserialize_partition(p.cells, path + " cells");
  part.run = std::move(p.run);
  part.run_hash = p.hash;
  part.sets = std::move(p.sets);
  return part;
}

PvsMerge merge_pvs_parts(const std::vector<std::string>& paths, const World& world) {
  PvsMerge merged;
  std::vector<bool> have;
  for (const std::string& path : paths) {
    PvsPart part = read_pvs_part(path, world);
    if (!merged.partition) {
      merged.partition = std::move(part.partition);
      merged.run = part.run;
      have.assign(size_t(merged.run.shards), false);
    } else if (serialize_partition(*part.partition) != serialize_partition(*merged.partition) ||
               part.run.engine != merged.run.engine || part.run.settings != merged.run.settings ||
               part.run.shards != merged.run.shards) {
      fail(path, "is a part of a different run than " + paths[0]);
    }
    if (part.run.shard < 0 || part.run.shard >= merged.run.shards || have[size_t(part.run.shard)])
      fail(path, "repeats shard " + std::to_string(part.run.shard));
    have[size_t(part.run.shard)] = true;
    merged.sets.merge(part.sets);
  }
  if (!merged.partition) fail("pvs --merge", "no part files given");
  return merged;
}

}  // namespace cellwalk::visibility
