// The stored stratified preprocessing of a world (seed 002 §3.1, §5.2.3; digest 002 §4): the
// sizing, the k-d viewcells, every cell's near list (section "stratified") and every baked cell's
// far faces (section "farfield"). Byte layout: docs/format.md, "`stratified` and `farfield`".
//
// Far-face codec: zstd per channel — colour RGBA8 and ids (object id + 1) lossless, depth as 8
// bits of disparity, q = 1 + min(254, ⌊254·(b/2)/d⌋) (0 = none), stored as differences along
// rows and decoded to the farthest distance of its step, so the angle measured from it is an
// upper bound. Lossless colour keeps the image comparison about parallax, not codec artefacts;
// ids must be exact for the missed-object count; zstd is already a dependency and decodes a 512²
// face in about a millisecond.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/far_field.hpp"
#include "cellwalk/systems/stratified/viewcells.hpp"

namespace cellwalk::stratified {

inline constexpr const char* kStratifiedSection = "stratified";
inline constexpr const char* kFarFieldSection = "farfield";

// What the preprocessing was run with.
struct StratifiedParams {
  float alpha = 0;        // radians
  float v = 0, b = 0;     // metres
  std::string sizing;     // "eq22", "strict", "numerical" or "given"
  int resolution = 512;   // texels per face side
  float far_level_texels = 0.5f;  // the bake's BakeSettings::max_texels (0: full detail)
};

struct StratifiedSizes {
  uint64_t cells = 0;
  uint64_t baked_cells = 0;        // cells with a far field (the others are skipped)
  uint64_t faces = 0;              // non-empty faces stored
  uint64_t near_ids = 0;           // Σ near-list lengths
  uint64_t near_bytes = 0;         // the near lists as stored
  uint64_t raw_face_bytes = 0;     // the faces' texels uncompressed: RGBA8 + u32 id + u8 depth
  uint64_t color_bytes = 0;        // compressed
  uint64_t id_bytes = 0;
  uint64_t depth_bytes = 0;
  double bake_seconds = 0;
};

// Encodes and decodes one cell's far-field record (exposed for the fuzzer and tests).
std::vector<uint8_t> encode_far_field(const CellFarField& field, float b, StratifiedSizes& sizes);
// Throws Error naming `where` for a damaged record, one whose faces are not `resolution`², or an
// id past `object_count`.
CellFarField decode_far_field(std::span<const uint8_t> bytes, float b, int resolution, uint64_t object_count,
                              const std::string& where);
// Adds a record's faces and encoded sizes to `sizes`. REQUIRES: a record encode_far_field made
// (or decode_far_field accepted) at this resolution.
void count_far_record(std::span<const uint8_t> record, int resolution, StratifiedSizes& sizes);

// Writes `out`: every section of `world` but old stratified ones, then "farfield", baking each
// computed cell of `cells.partition` (in id order) as `bake` gives its record (encode_far_field's
// bytes, written as they are), then "stratified". Atomic:
// nothing appears at `out` until it is complete, so `out` may be the world's own path.
// `progress` gets (cells done, cells to bake).
StratifiedSizes write_world_with_stratified(const World& world, const std::string& out, const Viewcells& cells,
                                            const StratifiedParams& params,
                                            const std::function<std::vector<uint8_t>(CellId)>& bake,
                                            const std::function<void(uint64_t, uint64_t)>& progress = {});

// Reads a world's stratified sections. Thread-safety: const methods may be called concurrently.
class StoredStratified {
 public:
  // Throws Error naming the command that makes them when the world has none, or naming the
  // section and offset when they are damaged.
  explicit StoredStratified(const World& world);
  ~StoredStratified();
  const StratifiedParams& params() const { return params_; }
  const ViewCellPartition& partition() const { return *partition_; }
  // The near list of a cell, ascending.
  std::vector<ObjectId> near(CellId cell) const;
  // The far field of a computed cell, read from the file and decoded.
  CellFarField far_field(CellId cell) const;
  // Bytes the cell's far-field record takes in the file (what a load reads).
  uint64_t far_field_bytes(CellId cell) const;
  // At most the bytes loading the cell holds at once: its record as read, six faces decoded
  // (colour, ids, depth) and its near list. What a loader reserves before it reads.
  uint64_t load_bound(CellId cell) const;
  // Memory held: parameters, the partition, the encoded near lists and the offsets.
  uint64_t resident_bytes() const;

 private:
  const World& world_;
  StratifiedParams params_;
  std::unique_ptr<ViewCellPartition> partition_;
  std::vector<uint8_t> near_bytes_;        // the near records
  std::vector<uint64_t> near_offsets_;     // cell_count + 1, into near_bytes_
  std::vector<uint64_t> far_offsets_;      // cell_count + 1, into the farfield section
};

}  // namespace cellwalk::stratified
