// Far-field baking that resumes and runs in shards (issue 17: "sharded and resumable like
// `pvs`"; seed 002 §3.1.2 is one process baking every cell). Each baked cell's record — as the
// farfield section stores it — is appended to a checkpoint as it completes (store/
// checkpoint_file.hpp), so a killed `stratify build` redoes only the cells after the last intact
// record. Shard i of N bakes the i-th of N equal runs of the cells to bake into a part file; the
// parts of one run are merged into the world. Byte layout: docs/format.md, "Stratify parts".
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/far_field.hpp"
#include "cellwalk/systems/stratified/stored_stratified.hpp"
#include "cellwalk/systems/stratified/viewcells.hpp"

namespace cellwalk::stratified {

// What makes two bakes the same run: the world's objects, the cells and which are baked, the
// parameters and the bake settings. Not the shard, so the parts of one run share it.
uint64_t bake_run_hash(const World& world, const Viewcells& cells, const StratifiedParams& params, const BakeSettings& bake);

// The records of one part or checkpoint file, indexed; read back from the file on demand.
// Thread-safety: none.
class BakePart {
 public:
  // An existing file. Throws Error naming it when it is not a stratify part or its header is
  // damaged; a torn or damaged record ends what is read (what follows is baked again).
  explicit BakePart(const std::string& path);
  const std::string& path() const { return path_; }
  uint64_t hash() const { return hash_; }
  int shard() const { return shard_; }
  int shards() const { return shards_; }
  bool has(CellId cell) const { return records_.count(cell) != 0; }
  size_t size() const { return records_.size(); }
  std::vector<CellId> cells() const;  // those with a record, ascending
  uint64_t valid_bytes() const { return valid_bytes_; }
  // The cell's record as stored, checked by decoding it. REQUIRES has(cell). Throws Error naming
  // the file when it changed since it was read or the record is damaged.
  std::vector<uint8_t> record(CellId cell, float b, int resolution, uint64_t object_count) const;
  // The cell's record, decoded; the same REQUIRES and errors.
  CellFarField far_field(CellId cell, float b, int resolution, uint64_t object_count) const;
 private:
  // Records a cell appended after `offset` with `bytes` payload bytes.
  void index(CellId cell, uint64_t offset, uint32_t bytes) { records_[cell] = {offset, bytes}; }
  BakePart() = default;
  friend class BakeLog;
  std::vector<uint8_t> read_record(CellId cell) const;  // unchecked
  std::string path_;
  uint64_t hash_ = 0;
  int shard_ = 0, shards_ = 1;
  uint64_t valid_bytes_ = 0;
  std::map<CellId, std::pair<uint64_t, uint32_t>> records_;  // cell -> (offset of its record, length)
};

// A checkpoint being written: resumes one of the same run, starts over after a damaged header
// (with a warning), refuses one of another run. Not thread-safe: one writer a file.
class BakeLog {
 public:
  // Throws Error naming `path` for another run's checkpoint or one it cannot write.
  BakeLog(const std::string& path, uint64_t hash, int shard, int shards);
  ~BakeLog();
  const BakePart& part() const { return part_; }
  size_t resumed() const { return resumed_; }
  // Appends the cell's far-field record (encode_far_field's bytes) in one write().
  void append(CellId cell, std::span<const uint8_t> record);

 private:
  BakePart part_;
  size_t resumed_ = 0;
  uint64_t end_ = 0;
  struct Writer;
  std::unique_ptr<Writer> writer_;
};

}  // namespace cellwalk::stratified
