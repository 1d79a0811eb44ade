// Per-cell visible sets for a whole world: parallel (TBB), resumable checkpoints, shards and
// merging, and the "cells"/"pvs"/"dov" sections. vLOD §2.3–§2.4 (Δs between face neighbours,
// digest 001 §3.3–§3.4); HDoV thesis §5.5 (per-cell DoV, digest 000 §3.9).
#include "visibility/pvs_builder.hpp"

#include <fcntl.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>
#include <xxhash.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>

#include "cellwalk/error.hpp"
#include "core/bytes.hpp"
#include "visibility/sampling_engine.hpp"
#include "visibility/set_codec.hpp"

namespace cellwalk::visibility {

namespace {

constexpr char kPartMagic[8] = {'C', 'W', 'P', 'V', 'S', 'C', 'K', '1'};
constexpr uint32_t kPvsVersion = 1;
constexpr uint8_t kNoSet = 0, kFullSet = 1, kDeltaSet = 2, kBitmaskSet = 3;

float parse_float(const std::string& spec, const std::string& text) {
  try {
    size_t used = 0;
    const float v = std::stof(text, &used);
    if (used == text.size() && v > 0.0f) return v;
  } catch (const std::exception&) {
  }
  fail("cells spec '" + spec + "'", "'" + text + "' is not a positive number");
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
  ByteWriter w;
  w.put(uint32_t(payload.size()));
  w.put(XXH3_64bits(payload.data(), payload.size()));
  w.put_array(std::span<const uint8_t>(payload));
  return std::move(w.bytes());
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

ParsedPart parse_part(const std::string& path, uint64_t object_count) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ByteReader r(bytes, path);
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
  // Records until the first torn or damaged one: everything after it is recomputed.
  while (r.remaining() >= 12) {
    const uint32_t len = r.get<uint32_t>("record length");
    const uint64_t sum = r.get<uint64_t>("record checksum");
    if (len > r.remaining()) break;
    const std::vector<uint8_t> payload = r.get_array<uint8_t>(len, "record");
    if (XXH3_64bits(payload.data(), payload.size()) != sum) break;
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
  return p;
}

// Appends records to a checkpoint with one write() each, so a crash tears at most the last.
class CheckpointWriter {
 public:
  CheckpointWriter(const std::string& path, uint64_t keep_bytes, std::span<const uint8_t> header) : path_(path) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT, 0644);
    if (fd_ < 0) fail(path, std::string("cannot open for writing: ") + std::strerror(errno));
    if (::ftruncate(fd_, off_t(keep_bytes)) != 0) fail(path, std::string("cannot truncate: ") + std::strerror(errno));
    ::lseek(fd_, off_t(keep_bytes), SEEK_SET);
    if (keep_bytes == 0) write_all(header);
  }
  ~CheckpointWriter() {
    ::fdatasync(fd_);
    ::close(fd_);
  }
  void write_all(std::span<const uint8_t> bytes) {
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) fail(path_, std::string("write failed: ") + std::strerror(errno));
      done += size_t(n);
    }
  }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace

std::unique_ptr<ViewCellPartition> make_partition(const std::string& spec, const World& world,
                                                  const EmbreeScene& scene) {
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
    if (parts.size() > 2) rules.threshold = uint64_t(parse_float(spec, parts[2]));
    if (parts.size() > 3) rules.max_depth = uint32_t(parse_float(spec, parts[3]));
    return make_octree_partition(region, rules, sampled_triangles(world), solid);
  }
  fail("cells spec '" + spec + "'", "expected grid:SIZE, grid3d:SIZE, kd:SIZE or octree[:ROOT[:THRESHOLD[:DEPTH]]]");
}

std::vector<CellId> shard_cells(const ViewCellPartition& partition, int shard, int shards) {
  if (shards < 1 || shard < 0 || shard >= shards) fail("--shard", "expected i/N with 0 <= i < N");
  const uint64_t n = partition.cell_count();
  std::vector<CellId> out;
  for (uint64_t c = n * uint64_t(shard) / uint64_t(shards); c < n * uint64_t(shard + 1) / uint64_t(shards); ++c)
    if (!partition.cell(CellId(c)).solid) out.push_back(CellId(c));
  return out;
}

CellSets compute_cell_sets(const World& world, const VisibilityEngine& engine,
                           const ViewCellPartition& partition, const PvsRun& run,
                           const std::string& checkpoint,
                           const std::function<void(uint64_t, uint64_t)>& progress) {
  const std::vector<uint8_t> cells = serialize_partition(partition);
  const uint64_t hash = run_hash(world, run, cells);
  CellSets sets;
  uint64_t keep = 0;
  if (std::filesystem::exists(checkpoint)) {
    ParsedPart old = parse_part(checkpoint, world.object_count());
    if (old.hash != hash)
      fail(checkpoint, "belongs to a different run (world, cells, engine, settings or shard); delete it to start over");
    sets = std::move(old.sets);
    keep = old.valid_bytes;
  }
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

namespace {

std::vector<uint8_t> encode_dov_section(const ViewCellPartition& partition, const CellSets& sets) {
  ByteWriter w;
  w.put(kPvsVersion);
  w.put(uint32_t(partition.cell_count()));
  uint64_t offset = 0;
  for (CellId c = 0; c <= partition.cell_count(); ++c) {
    w.put(offset);
    if (c == partition.cell_count()) break;
    if (auto it = sets.find(c); it != sets.end()) offset += it->second.dov.size() * sizeof(float);
  }
  for (const auto& [cell, set] : sets) w.put_array(std::span<const float>(set.dov));
  return std::move(w.bytes());
}

// Each cell's record: the smallest of its gap-coded ids, its bitmask and a Δ from an earlier
// face neighbour stored on its own (gap-coded or bitmask). References are never Δs, so any cell
// decodes in at most two steps, and no record is longer than a bitmask and its tag byte.
std::vector<uint8_t> encode_pvs_section(const ViewCellPartition& partition, const CellSets& sets,
                                        uint64_t object_count, const PvsRun& run, PvsSizes& sizes) {
  std::vector<uint8_t> records;
  std::vector<uint64_t> offsets;
  std::vector<bool> full(partition.cell_count(), false);
  for (CellId c = 0; c < partition.cell_count(); ++c) {
    offsets.push_back(records.size());
    auto it = sets.find(c);
    if (it == sets.end()) {
      records.push_back(kNoSet);
      continue;
    }
    const std::vector<ObjectId>& ids = it->second.objects;
    std::vector<uint8_t> best;
    best.push_back(kFullSet);
    append_set(best, ids);
    sizes.full_bytes += best.size();
    if (bitmask_bytes(object_count) < best.size() - 1) {
      best.assign(1, kBitmaskSet);
      append_bitmask(best, ids, object_count);
    }
    for (CellId n : partition.face_neighbours(c)) {
      auto nt = sets.find(n);
      if (nt == sets.end()) continue;
      std::vector<uint8_t> delta;
      append_delta(delta, set_delta(nt->second.objects, ids));
      if (n > c) {  // each face pair counted once
        ++sizes.face_pairs;
        sizes.face_delta_bytes += delta.size();
      }
      if (n >= c || !full[n]) continue;
      std::vector<uint8_t> candidate{kDeltaSet};
      put_varint(candidate, n);
      candidate.insert(candidate.end(), delta.begin(), delta.end());
      if (candidate.size() < best.size()) best = std::move(candidate);
    }
    full[c] = best[0] != kDeltaSet;
    sizes.delta_cells += full[c] ? 0 : 1;
    ++sizes.cells_with_sets;
    sizes.ids += ids.size();
    sizes.bitmask_bytes += bitmask_bytes(object_count);
    records.insert(records.end(), best.begin(), best.end());
  }
  offsets.push_back(records.size());
  sizes.cells = partition.cell_count();
  sizes.stored_bytes = records.size();
  ByteWriter w;
  w.put(kPvsVersion);
  w.put(uint32_t(partition.cell_count()));
  w.put(uint32_t(object_count));
  w.put(uint32_t(run.conservative ? 1 : 0));
  w.put_string(run.engine);
  w.put_array(std::span<const uint64_t>(offsets));
  w.put_array(std::span<const uint8_t>(records));
  return std::move(w.bytes());
}

void write_section(WorldWriter& w, const char* name, std::span<const uint8_t> bytes) {
  w.begin_section(name);
  w.write(bytes);
  w.end_section();
}

}  // namespace

PvsSizes write_world_with_pvs(const World& world, const std::string& out, const ViewCellPartition& partition,
                              const CellSets& sets, const PvsRun& run) {
  for (CellId c = 0; c < partition.cell_count(); ++c)
    if (!partition.cell(c).solid && !sets.count(c))
      fail("pvs", "cell " + std::to_string(c) + " has no visible set; compute or merge every shard first");
  PvsSizes sizes;
  const std::vector<uint8_t> pvs = encode_pvs_section(partition, sets, world.object_count(), run, sizes);
  const bool with_dov = !sets.empty() && !sets.begin()->second.dov.empty();
  const std::vector<uint8_t> dov = with_dov ? encode_dov_section(partition, sets) : std::vector<uint8_t>{};
  sizes.dov_bytes = dov.size();
  WorldWriter w(out, world.file().page_size());
  constexpr uint64_t kChunk = 1 << 20;
  for (const SectionInfo& s : world.file().sections()) {
    if (s.name == kCellsSection || s.name == kPvsSection || s.name == kDovSection) continue;
    w.begin_section(s.name);
    for (uint64_t at = 0; at < s.bytes; at += kChunk) w.write(world.file().read(s, at, std::min(kChunk, s.bytes - at)));
    w.end_section();
  }
  write_section(w, kCellsSection, serialize_partition(partition));
  write_section(w, kPvsSection, pvs);
  if (with_dov) write_section(w, kDovSection, dov);
  w.finish();
  return sizes;
}

StoredPvs::StoredPvs(const World& world) : object_count_(world.object_count()) {
  const std::string path = world.file().path();
  partition_ = deserialize_partition(world.file().read_all(kCellsSection), path + " section cells");
  pvs_ = world.file().read_all(kPvsSection);
  ByteReader r(pvs_, path + " section pvs");
  if (r.get<uint32_t>("version") != kPvsVersion) r.error("unknown pvs version");
  const uint32_t cells = r.get<uint32_t>("cell count");
  if (cells != partition_->cell_count()) r.error("cell count differs from the cells section");
  if (r.get<uint32_t>("object count") != object_count_) r.error("object count differs from the world's");
  conservative_ = r.get<uint32_t>("flags") & 1;
  engine_ = r.get_string("engine");
  offsets_ = r.get_array<uint64_t>(uint64_t(cells) + 1, "offsets");
  const uint64_t base = r.offset();
  for (size_t i = 0; i < offsets_.size(); ++i) {
    offsets_[i] += base;
    if (offsets_[i] > pvs_.size() || (i > 0 && offsets_[i] < offsets_[i - 1])) r.error("bad record offsets");
  }
  if (world.file().has_section(kDovSection)) {
    dov_ = world.file().read_all(kDovSection);
    ByteReader d(dov_, path + " section dov");
    if (d.get<uint32_t>("version") != kPvsVersion || d.get<uint32_t>("cell count") != cells) d.error("does not match pvs");
    dov_offsets_ = d.get_array<uint64_t>(uint64_t(cells) + 1, "offsets");
    for (uint64_t& o : dov_offsets_) {
      o += d.offset();
      if (o > dov_.size()) d.error("bad offsets");
    }
  }
}

std::span<const uint8_t> StoredPvs::record(CellId cell) const {
  if (cell >= partition_->cell_count()) fail("pvs", "cell " + std::to_string(cell) + " out of range");
  return std::span(pvs_).subspan(offsets_[cell], offsets_[cell + 1] - offsets_[cell]);
}

std::vector<ObjectId> StoredPvs::decode(CellId cell, int depth) const {
  const std::span<const uint8_t> rec = record(cell);
  const std::string where = "pvs cell " + std::to_string(cell);
  if (rec.empty()) fail(where, "empty record");
  size_t pos = 1;
  std::vector<ObjectId> ids;
  if (rec[0] == kFullSet) {
    ids = read_set(rec, pos, where, object_count_);
  } else if (rec[0] == kBitmaskSet) {
    ids = read_bitmask(rec, pos, where, object_count_);
  } else if (rec[0] == kDeltaSet && depth == 0) {
    const uint64_t ref = get_varint(rec, pos, where);
    if (ref >= partition_->cell_count()) fail(where, "Δ refers to cell " + std::to_string(ref) + ", past the last");
    const SetDelta delta = read_delta(rec, pos, where, object_count_);
    ids = apply_delta(decode(CellId(ref), depth + 1), delta);
  } else {
    fail(where, "bad record form " + std::to_string(rec[0]) + (depth > 0 ? " (a Δ must refer to a set stored on its own)" : ""));
  }
  if (pos != rec.size()) fail(where, std::to_string(rec.size() - pos) + " bytes after the set: record damaged");
  return ids;
}

std::optional<VisibleSet> StoredPvs::set(CellId cell) const {
  const std::span<const uint8_t> rec = record(cell);
  if (!rec.empty() && rec[0] == kNoSet) return std::nullopt;
  VisibleSet set;
  set.objects = decode(cell, 0);
  if (has_dov()) {
    const uint64_t bytes = dov_offsets_[cell + 1] - dov_offsets_[cell];
    if (dov_offsets_[cell + 1] < dov_offsets_[cell] || bytes != set.objects.size() * sizeof(float))
      fail("dov cell " + std::to_string(cell), "length does not match its set");
    set.dov.resize(set.objects.size());
    std::memcpy(set.dov.data(), dov_.data() + dov_offsets_[cell], bytes);
  }
  return set;
}

}  // namespace cellwalk::visibility
