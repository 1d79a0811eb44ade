// The vlod section: per-face Δs of vLODs and key-cell vLODs (seed 001 §2.3–§2.4, digest 001
// §3.3–§3.4 and §4 [ours]). Each record is stored in the smallest of the id-set codecs.
// Layout in docs/format.md, "The vlod section". Run-time code: no Embree, no GL.
#include "cellwalk/visibility/stored_vlod.hpp"

#include <algorithm>
#include <deque>
#include <iterator>

#include "cellwalk/core/error.hpp"
#include "cellwalk/visibility/disk_order.hpp"
#include "core/bytes.hpp"

namespace cellwalk::visibility {

namespace {

// 2: pieces numbered in the geometry section's byte order (1: in the level table's order).
constexpr uint32_t kVlodVersion = 2;
constexpr uint8_t kHasVlod = 1;

// Cells within `steps` face steps of `from` over cells with a vLOD (BFS).
bool key_within(const ViewCellPartition& partition, const std::vector<bool>& has, const std::vector<bool>& key,
                CellId from, int steps) {
  std::deque<std::pair<CellId, int>> todo{{from, 0}};
  std::vector<CellId> seen{from};
  while (!todo.empty()) {
    const auto [c, d] = todo.front();
    todo.pop_front();
    if (key[c]) return true;
    if (d == steps) continue;
    for (CellId n : partition.face_neighbours(c))
      if (has[n] && std::find(seen.begin(), seen.end(), n) == seen.end()) {
        seen.push_back(n);
        todo.push_back({n, d + 1});
      }
  }
  return false;
}

// The codec that stores `parts` (concatenated records) in the fewest bytes.
IdCodec smallest(std::initializer_list<std::span<const PieceId>> parts) {
  IdCodec best = IdCodec::kVarintGaps;
  uint64_t best_bytes = UINT64_MAX;
  for (IdCodec c : kIdCodecs) {
    uint64_t bytes = 0;
    for (std::span<const PieceId> p : parts) bytes += encoded_size(c, p);
    if (bytes < best_bytes) best = c, best_bytes = bytes;
  }
  return best;
}

void append_record(std::vector<uint8_t>& out, std::initializer_list<std::span<const PieceId>> parts) {
  const IdCodec codec = smallest(parts);
  out.push_back(uint8_t(codec));
  for (std::span<const PieceId> p : parts) encode_ids(codec, p, out);
}

IdCodec codec_of(uint8_t tag, const std::string& where) {
  if (tag >= std::size(kIdCodecs)) fail(where, "unknown id codec " + std::to_string(tag) + " (the file is damaged)");
  return kIdCodecs[tag];
}

// The pieces along the Morton curve of their objects' box centres, an object's levels together.
std::vector<uint32_t> morton_piece_order(const World& world, const PieceTable& pieces) {
  std::vector<std::array<float, 3>> centres(pieces.count());
  for (PieceId p = 0; p < pieces.count(); ++p) {
    const Vec3 c = world.object(pieces.object(p)).bounds.center();
    centres[p] = {c.x, c.y, c.z};
  }
  return morton_order(centres);
}

// Every level's offset in the geometry section, each object's levels in turn.
std::vector<uint64_t> level_offsets(const World& world) {
  std::vector<uint64_t> offsets;
  for (ObjectId id = 0; id < world.object_count(); ++id)
    for (uint32_t level = 0; level < world.object(id).lod_count; ++level) offsets.push_back(world.lod(id, level).offset);
  return offsets;
}

// R(M) of the crossings' additions in the file's layout, the Morton order (the seed's baseline)
// and the TSP order (its search bounded to seconds).
PieceOrders measure_disk_order(const std::vector<std::vector<uint32_t>>& rows, const World& world,
                               const PieceTable& table, VlodSizes& sizes) {
  // Pieces are numbered in the file's byte order: its layout is the identity.
  PieceOrders orders{identity_order(uint32_t(table.count())), morton_piece_order(world, table), {}};
  sizes.runs_world_order = total_runs(rows, orders.file);
  sizes.runs_morton_order = total_runs(rows, orders.morton);
  DiskOrderOptions options;
  options.max_iterations = 2000;
  options.max_seconds = 5;
  // The exact neighbour lists cost Σ |row|²: beyond a few seconds' worth, the sampled ones.
  double pairs = 0;
  for (const auto& row : rows) pairs += double(row.size()) * double(row.size());
  options.use_sampling = pairs > 2e8;
  orders.tsp = disk_order(columns_from_rows(rows, uint32_t(table.count())), orders.file, options);
  sizes.runs_tsp_order = total_runs(rows, orders.tsp);
  return orders;
}

// Each level's offset (as level_offsets() orders them) once the levels lie in `order`.
std::vector<uint64_t> offsets_in_order(const World& world, const PieceTable& pieces, const std::vector<uint32_t>& order) {
  std::vector<uint64_t> first(world.object_count() + 1, 0);
  for (ObjectId id = 0; id < world.object_count(); ++id) first[id + 1] = first[id] + world.object(id).lod_count;
  std::vector<uint64_t> offsets(first.back());
  uint64_t at = 0;
  for (uint32_t p : order) {
    offsets[first[pieces.object(p)] + pieces.level(p)] = at;
    at += world.lod(pieces.object(p), pieces.level(p)).bytes;
  }
  return offsets;
}

// The geometry section with the levels in `order`, and the lods section with each entry's offset
// moved with its level to `offsets` (offsets_in_order; an entry's first 8 bytes, docs/format.md).
std::vector<NamedSection> laid_out_geometry(const World& world, const PieceTable& pieces,
                                            const std::vector<uint32_t>& order, const std::vector<uint64_t>& offsets) {
  constexpr size_t kLodEntry = 24;
  std::vector<uint8_t> lods = world.file().read_all("lods");
  size_t slot = 0;
  for (ObjectId id = 0; id < world.object_count(); ++id)
    for (uint32_t level = 0; level < world.object(id).lod_count; ++level, ++slot) {
      const uint64_t entry = world.object(id).first_lod + level;
      if ((entry + 1) * kLodEntry > lods.size()) fail(world.file().path(), "section lods is shorter than its objects say (the file is damaged)");
      for (int b = 0; b < 8; ++b) lods[entry * kLodEntry + size_t(b)] = uint8_t(offsets[slot] >> (8 * b));
    }
  NamedSection geometry{"geometry", {}, [&world, &pieces, order](WorldWriter& w) {
                          for (uint32_t p : order) w.write(world.read_level(pieces.object(p), pieces.level(p)));
                        }};
  return {std::move(geometry), {"lods", std::move(lods), {}}};
}

// The ids in `ids` renumbered by `to` (old id -> new), ascending.
void renumber(std::vector<PieceId>& ids, const std::vector<PieceId>& to) {
  for (PieceId& p : ids) p = to[p];
  std::sort(ids.begin(), ids.end());
}

}  // namespace

PieceTable::PieceTable(const World& world) : PieceTable(world, level_offsets(world)) {}

PieceTable::PieceTable(const World& world, std::span<const uint64_t> offsets) {
  first_.reserve(world.object_count());
  std::vector<std::pair<ObjectId, uint32_t>> levels;  // in object and level order
  for (ObjectId id = 0; id < world.object_count(); ++id) {
    first_.push_back(uint32_t(levels.size()));
    for (uint32_t level = 0; level < world.object(id).lod_count; ++level) levels.push_back({id, level});
  }
  if (offsets.size() != levels.size()) fail(world.file().path(), "offsets for " + std::to_string(offsets.size()) + " levels, the world has " + std::to_string(levels.size()));
  std::vector<uint32_t> by_offset = identity_order(uint32_t(levels.size()));
  std::stable_sort(by_offset.begin(), by_offset.end(), [&](uint32_t a, uint32_t b) { return offsets[a] < offsets[b]; });
  piece_.resize(levels.size());
  object_.reserve(levels.size());
  level_.reserve(levels.size());
  for (uint32_t slot : by_offset) {
    piece_[slot] = PieceId(object_.size());
    object_.push_back(levels[slot].first);
    level_.push_back(levels[slot].second);
  }
}

uint64_t PieceTable::resident_bytes() const {
  return first_.capacity() * sizeof(uint32_t) + piece_.capacity() * sizeof(PieceId) +
         object_.capacity() * sizeof(ObjectId) + level_.capacity() * sizeof(uint32_t);
}

std::vector<PieceId> vlod_pieces(const World& world, const PieceTable& pieces, const ViewCellPartition& partition,
                                 CellId cell, std::span<const ObjectId> set, const CellLodRule& rule) {
  std::vector<PieceId> out;
  out.reserve(set.size());
  const Aabb& box = partition.cell(cell).box;
  for (ObjectId id : set) out.push_back(pieces.piece(id, cell_level(world, id, box, rule)));
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

// Every cell's vLOD and which cells are key cells.
struct CellVlods {
  std::vector<std::vector<PieceId>> vlod;  // per cell, ascending; empty without one
  std::vector<bool> has, key;
};

CellVlods cell_vlods(const World& world, const PieceTable& pieces, const ViewCellPartition& partition,
                     const CellSets& sets, const CellLodRule& rule, int key_spacing, VlodSizes& sizes) {
  const size_t cells = partition.cell_count();
  CellVlods v{std::vector<std::vector<PieceId>>(cells), std::vector<bool>(cells, false), std::vector<bool>(cells, false)};
  for (const auto& [c, set] : sets) {
    v.vlod[c] = vlod_pieces(world, pieces, partition, c, set.objects, rule);
    v.has[c] = true;
    sizes.vlod_ids += v.vlod[c].size();
    ++sizes.cells_with_vlod;
  }
  for (CellId c = 0; c < cells; ++c)
    if (v.has[c] && !key_within(partition, v.has, v.key, c, key_spacing)) v.key[c] = true;
  return v;
}

// The Δ of a shared face, stored once, from the lower cell id to the higher.
struct FaceDelta {
  CellId from, to;
  VlodDelta d;
};

// In the order the records are written: by `from`, then its faces' order.
std::vector<FaceDelta> face_deltas(const ViewCellPartition& partition, const CellVlods& v) {
  std::vector<FaceDelta> out;
  for (CellId c = 0; c < partition.cell_count(); ++c) {
    if (!v.has[c]) continue;
    for (CellId n : partition.face_neighbours(c)) {
      if (n <= c || !v.has[n]) continue;
      FaceDelta f{c, n, {}};
      std::set_difference(v.vlod[n].begin(), v.vlod[n].end(), v.vlod[c].begin(), v.vlod[c].end(), std::back_inserter(f.d.added));
      std::set_difference(v.vlod[c].begin(), v.vlod[c].end(), v.vlod[n].begin(), v.vlod[n].end(), std::back_inserter(f.d.removed));
      out.push_back(std::move(f));
    }
  }
  return out;
}

// §3's matrix: the pieces each crossing adds (A one way, R the other).
std::vector<std::vector<uint32_t>> added_rows(const std::vector<FaceDelta>& deltas) {
  std::vector<std::vector<uint32_t>> rows;
  for (const FaceDelta& f : deltas)
    for (const std::vector<PieceId>* row : {&f.d.added, &f.d.removed})
      if (!row->empty()) rows.push_back(*row);
  return rows;
}

// The section (docs/format.md): header, index of the cells and their faces, then the records,
// each key cell's vLOD before the Δs of its faces to higher cells.
std::vector<uint8_t> encode_section(const ViewCellPartition& partition, const CellLodRule& rule, uint64_t piece_count,
                                    const CellVlods& v, const std::vector<FaceDelta>& deltas, VlodSizes& sizes) {
  const size_t cells = partition.cell_count();
  std::vector<uint8_t> records;
  struct FaceEntry {
    CellId neighbour;
    bool forward;
    uint64_t offset;
    uint32_t bytes;
  };
  std::vector<std::vector<FaceEntry>> faces(cells);
  std::vector<std::pair<uint64_t, uint32_t>> key_records(cells, {0, 0});
  size_t next = 0;
  for (CellId c = 0; c < cells; ++c) {
    if (v.key[c]) {
      const uint64_t at = records.size();
      append_record(records, {v.vlod[c]});
      key_records[c] = {at, uint32_t(records.size() - at)};
      sizes.keyframe_bytes += records.size() - at;
      ++sizes.keyframes;
    }
    for (; next < deltas.size() && deltas[next].from == c; ++next) {
      const VlodDelta& d = deltas[next].d;
      const uint64_t at = records.size();
      append_record(records, {d.added, d.removed});
      const uint32_t bytes = uint32_t(records.size() - at);
      faces[c].push_back({deltas[next].to, true, at, bytes});
      faces[deltas[next].to].push_back({c, false, at, bytes});
      ++sizes.face_pairs;
      sizes.delta_ids += d.added.size() + d.removed.size();
      sizes.delta_bytes += bytes;
      sizes.bitmask_bytes += 2 * ((piece_count + 7) / 8);
      sizes.list_bytes += 4 * (d.added.size() + d.removed.size());
      for (size_t i = 0; i < std::size(kIdCodecs); ++i)
        sizes.codec_bytes[i] += 1 + encoded_size(kIdCodecs[i], d.added) + encoded_size(kIdCodecs[i], d.removed);
    }
  }
  ByteWriter index;
  const std::vector<uint8_t> cells_bytes = serialize_partition(partition);
  index.put(uint64_t(cells_bytes.size()));
  index.put_array(std::span<const uint8_t>(cells_bytes));
  index.put_string(to_string(rule));
  index.put(uint32_t(cells));
  index.put(uint32_t(piece_count));
  for (CellId c = 0; c < cells; ++c) {
    index.put(uint8_t(v.has[c] ? kHasVlod : 0));
    index.put(key_records[c].first);
    index.put(key_records[c].second);
    index.put(uint32_t(faces[c].size()));
    for (const FaceEntry& f : faces[c]) {
      index.put(f.neighbour);
      index.put(uint8_t(f.forward));
      index.put(f.offset);
      index.put(f.bytes);
    }
  }
  ByteWriter out;
  out.put(kVlodVersion);
  out.put(uint64_t(index.size()));
  out.put_array(std::span<const uint8_t>(index.bytes()));
  out.put_array(std::span<const uint8_t>(records));
  sizes.cells = cells;
  sizes.section_bytes = out.size();
  return std::move(out.bytes());
}

}  // namespace

std::string disk_layout_name(DiskLayout layout) {
  switch (layout) {
    case DiskLayout::kKeep: return "keep";
    case DiskLayout::kMorton: return "morton";
    case DiskLayout::kTsp: return "tsp";
  }
  return "?";
}

std::vector<std::string> disk_layout_names() { return {"keep", "morton", "tsp"}; }

DiskLayout parse_disk_layout(const std::string& name) {
  for (DiskLayout l : {DiskLayout::kKeep, DiskLayout::kMorton, DiskLayout::kTsp})
    if (disk_layout_name(l) == name) return l;
  fail("--disk-order", "unknown layout '" + name + "'; use keep, morton or tsp");
}

VlodSizes write_world_with_vlod(const World& world, const std::string& out, const ViewCellPartition& partition,
                                const CellSets& sets, const CellLodRule& rule, DiskLayout layout, int key_spacing,
                                PieceOrders* orders) {
  for (CellId c = 0; c < partition.cell_count(); ++c)
    if (partition.cell(c).computed() && !sets.count(c))
      fail("pvs", "cell " + std::to_string(c) + " has no vLOD; compute or merge every shard first");
  VlodSizes sizes;
  const PieceTable pieces(world);  // outlives the geometry's writer
  CellVlods vlods = cell_vlods(world, pieces, partition, sets, rule, key_spacing, sizes);
  std::vector<FaceDelta> deltas = face_deltas(partition, vlods);
  PieceOrders measured = measure_disk_order(added_rows(deltas), world, pieces, sizes);
  sizes.runs_written = layout == DiskLayout::kKeep     ? sizes.runs_world_order
                       : layout == DiskLayout::kMorton ? sizes.runs_morton_order
                                                       : sizes.runs_tsp_order;
  std::vector<NamedSection> geometry;
  if (layout != DiskLayout::kKeep) {
    // §2.4: the pieces renumbered in the new layout, so its runs are runs of ids.
    const std::vector<uint32_t>& order = layout == DiskLayout::kMorton ? measured.morton : measured.tsp;
    const std::vector<uint64_t> offsets = offsets_in_order(world, pieces, order);
    const PieceTable laid_out(world, offsets);
    std::vector<PieceId> to(pieces.count());
    for (PieceId p = 0; p < pieces.count(); ++p) to[p] = laid_out.piece(pieces.object(p), pieces.level(p));
    for (std::vector<PieceId>& v : vlods.vlod) renumber(v, to);
    for (FaceDelta& f : deltas) renumber(f.d.added, to), renumber(f.d.removed, to);
    geometry = laid_out_geometry(world, pieces, order, offsets);
  }
  std::vector<NamedSection> sections{{kVlodSection, encode_section(partition, rule, pieces.count(), vlods, deltas, sizes), {}}};
  std::move(geometry.begin(), geometry.end(), std::back_inserter(sections));
  write_world_sections(world, out, sections);
  if (orders) *orders = std::move(measured);
  return sizes;
}

StoredVlod::StoredVlod(const World& world) : world_(world), pieces_(world) {
  const std::string path = world.file().path();
  if (!world.file().has_section(kVlodSection))
    fail(path, "has no vLOD sets; run `cellwalk pvs " + path + " --engine vlod` first");
  const SectionInfo& section = world.file().section(kVlodSection);
  const std::string where = path + " section vlod";
  if (section.bytes < 12) fail(where, "truncated header (the file is damaged)");
  const std::vector<uint8_t> head = world.file().read(section, 0, 12);
  ByteReader h(head, where);
  if (h.get<uint32_t>("version") != kVlodVersion) h.error("unknown vlod version; rerun `cellwalk pvs --engine vlod`");
  const uint64_t index_bytes = h.get<uint64_t>("index size");
  if (index_bytes > section.bytes - 12) h.error("index larger than the section (the file is damaged)");
  const std::vector<uint8_t> index = world.file().read(section, 12, index_bytes);
  ByteReader r(index, where, 12);
  const std::vector<uint8_t> cells_bytes = r.get_array<uint8_t>(r.get<uint64_t>("cells size"), "cells");
  partition_ = deserialize_partition(cells_bytes, where + " cells");
  rule_ = parse_cell_lod_rule(r.get_string("rule"), where);
  const uint32_t cells = r.get<uint32_t>("cell count");
  if (cells != partition_->cell_count()) r.error("cell count differs from the partition's");
  if (r.get<uint32_t>("piece count") != pieces_.count()) r.error("piece count differs from the world's level table");
  const uint64_t records_start = 12 + index_bytes, records_bytes = section.bytes - records_start;
  cells_.resize(cells);
  for (CellId c = 0; c < cells; ++c) {
    Cell& cell = cells_[c];
    cell.has_vlod = r.get<uint8_t>("flags") & kHasVlod;
    cell.key_offset = r.get<uint64_t>("key offset");
    cell.key_bytes = r.get<uint32_t>("key bytes");
    if (cell.key_offset + cell.key_bytes > records_bytes) r.error("key record past the section's end");
    const uint32_t count = r.get<uint32_t>("face count");
    if (count > r.remaining() / 17) r.error("face count larger than the index holds");
    for (uint32_t i = 0; i < count; ++i) {
      Face f{r.get<uint32_t>("neighbour"), r.get<uint8_t>("direction") != 0, r.get<uint64_t>("offset"),
             r.get<uint32_t>("bytes")};
      if (f.neighbour >= cells || f.offset + f.bytes > records_bytes) r.error("face record out of range");
      f.offset += records_start;
      cell.faces.push_back(f);
    }
    cell.key_offset += records_start;
  }
  if (r.remaining() != 0) r.error("bytes after the index (the file is damaged)");
}

std::vector<uint8_t> StoredVlod::read(uint64_t offset, uint32_t bytes) const {
  bytes_read_ += bytes;
  return world_.file().read(world_.file().section(kVlodSection), offset, bytes);
}

std::vector<PieceId> StoredVlod::key_vlod(CellId cell) const {
  const Cell& c = cells_.at(cell);
  const std::string where = world_.file().path() + " section vlod, key cell " + std::to_string(cell);
  if (c.key_bytes == 0) fail(where, "is not a key cell");
  const std::vector<uint8_t> bytes = read(c.key_offset, c.key_bytes);
  size_t pos = 1;
  std::vector<PieceId> ids = decode_ids(codec_of(bytes[0], where), bytes, pos, where, pieces_.count());
  if (pos != bytes.size()) fail(where, "bytes after the record (the file is damaged)");
  return ids;
}

std::optional<VlodDelta> StoredVlod::delta(CellId from, CellId to) const {
  const Cell& c = cells_.at(from);
  for (const Face& f : c.faces) {
    if (f.neighbour != to) continue;
    const std::string where = world_.file().path() + " section vlod, Δ " + std::to_string(from) + "→" + std::to_string(to);
    const std::vector<uint8_t> bytes = read(f.offset, f.bytes);
    if (bytes.empty()) fail(where, "empty record (the file is damaged)");
    const IdCodec codec = codec_of(bytes[0], where);
    size_t pos = 1;
    VlodDelta d;
    d.added = decode_ids(codec, bytes, pos, where, pieces_.count());
    d.removed = decode_ids(codec, bytes, pos, where, pieces_.count());
    if (pos != bytes.size()) fail(where, "bytes after the record (the file is damaged)");
    if (!f.forward) std::swap(d.added, d.removed);
    return d;
  }
  return std::nullopt;
}

std::vector<CellId> StoredVlod::neighbours(CellId cell) const {
  std::vector<CellId> out;
  for (const Face& f : cells_.at(cell).faces) out.push_back(f.neighbour);
  return out;
}

uint64_t StoredVlod::resident_bytes() const {
  uint64_t bytes = cells_.size() * sizeof(Cell) + pieces_.resident_bytes() +
                   partition_->cell_count() * (sizeof(ViewCell) + 6 * sizeof(CellId));
  for (const Cell& c : cells_) bytes += c.faces.capacity() * sizeof(Face);
  return bytes;
}

uint64_t StoredVlod::bytes_read() const { return bytes_read_.load(); }

}  // namespace cellwalk::visibility
