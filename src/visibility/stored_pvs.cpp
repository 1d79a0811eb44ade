// The stored visible sets of a world: the "cells", "pvs" and "dov" sections, written and read.
// The sets are stored as vLOD stores them (digest 001 §3.3–§3.4): gap-coded ids, or a Δ from a
// face neighbour, or (ours) a plain bitmask, whichever is the smallest; HDoV thesis §5.5 (per-cell
// DoV). Layouts in docs/format.md, "Visibility sections". Run-time code: no Embree, no GL.
#include "cellwalk/visibility/stored_pvs.hpp"

#include <algorithm>
#include <cstring>

#include "cellwalk/core/error.hpp"
#include "core/bytes.hpp"
#include "visibility/set_codec.hpp"

namespace cellwalk::visibility {

namespace {

constexpr uint32_t kPvsVersion = 1;
constexpr uint8_t kNoSet = 0, kFullSet = 1, kDeltaSet = 2, kBitmaskSet = 3;


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

}  // namespace

PvsSizes write_world_with_pvs(const World& world, const std::string& out, const ViewCellPartition& partition,
                              const CellSets& sets, const PvsRun& run) {
  for (CellId c = 0; c < partition.cell_count(); ++c)
    if (partition.cell(c).computed() && !sets.count(c))
      fail("pvs", "cell " + std::to_string(c) + " has no visible set; compute or merge every shard first");
  PvsSizes sizes;
  std::vector<NamedSection> sections{{kCellsSection, serialize_partition(partition)},
                                     {kPvsSection, encode_pvs_section(partition, sets, world.object_count(), run, sizes)}};
  if (!sets.empty() && !sets.begin()->second.dov.empty()) {
    sections.push_back({kDovSection, encode_dov_section(partition, sets)});
    sizes.dov_bytes = sections.back().bytes.size();
  }
  write_world_sections(world, out, sections, {kCellsSection, kPvsSection, kDovSection});
  return sizes;
}

void write_world_sections(const World& world, const std::string& out, const std::vector<NamedSection>& sections,
                          const std::vector<std::string>& drop) {
  auto named = [&](const std::string& name) {
    return std::find(drop.begin(), drop.end(), name) != drop.end() ||
           std::any_of(sections.begin(), sections.end(), [&](const NamedSection& s) { return s.name == name; });
  };
  WorldWriter w(out, world.file().page_size());
  constexpr uint64_t kChunk = 1 << 20;
  for (const SectionInfo& s : world.file().sections()) {
    if (named(s.name)) continue;
    w.begin_section(s.name);
    for (uint64_t at = 0; at < s.bytes; at += kChunk) w.write(world.file().read(s, at, std::min(kChunk, s.bytes - at)));
    w.end_section();
  }
  for (const NamedSection& s : sections) {
    w.begin_section(s.name);
    if (s.stream) s.stream(w);
    else w.write(s.bytes);
    w.end_section();
  }
  w.finish();
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

uint64_t StoredPvs::resident_bytes() const {
  return pvs_.size() + dov_.size() + (offsets_.size() + dov_offsets_.size()) * sizeof(uint64_t) +
         partition_->cell_count() * (sizeof(ViewCell) + 6 * sizeof(CellId));  // boxes and neighbour lists
}

std::optional<VisibleSet> StoredPvs::set(CellId cell) const {
  const std::span<const uint8_t> rec = record(cell);
  if (partition_->cell(cell).skipped)
    fail("pvs cell " + std::to_string(cell), "has no set: `cellwalk pvs --along` left it out; rerun pvs with a larger --along-margin or without --along");
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
