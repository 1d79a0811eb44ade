// The stored vLODs of a world (section "vlod"; docs/format.md, "The vlod section"): per shared
// face, the Δ between the two cells' vLODs, and full vLODs for sparse key cells, for start-up
// and teleports (seed 001 §2.3–§2.4; digest 001 §3.3, §4 and its [ours] keyframes).
// An id of a vLOD is a *piece*: one level of one object, so a cell change that only coarsens an
// object is a Δ too. Pieces are numbered in the order their encoded levels lie in the geometry
// section (§2.4's renumbering): once §3's layout is applied, the pieces a crossing adds are runs
// of consecutive ids, which the run codecs store as one.
// Depends on the store only (no Embree, no GL), so a server can stream Δs.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/store/world.hpp"
#include "cellwalk/visibility/cell_lod.hpp"
#include "cellwalk/visibility/id_codec.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"

namespace cellwalk::visibility {

inline constexpr const char* kVlodSection = "vlod";

using PieceId = uint32_t;

// The pieces of every object's levels, numbered by their offsets in the geometry section (ties,
// which only empty levels make, in object and level order), and back.
class PieceTable {
 public:
  explicit PieceTable(const World& world);
  // Numbered as if the levels lay at `offsets`: one per level, each object's levels in turn
  // (object 0 level 0, object 0 level 1, ...). REQUIRES offsets.size() == the world's level count.
  PieceTable(const World& world, std::span<const uint64_t> offsets);
  PieceId piece(ObjectId id, uint32_t level) const { return piece_[first_[id] + level]; }
  ObjectId object(PieceId p) const { return object_[p]; }
  uint32_t level(PieceId p) const { return level_[p]; }
  uint64_t count() const { return object_.size(); }
  uint64_t resident_bytes() const;

 private:
  std::vector<uint32_t> first_;    // per object: the index of its level 0 among every level
  std::vector<PieceId> piece_;     // per level, in object and level order
  std::vector<ObjectId> object_;   // per piece
  std::vector<uint32_t> level_;    // per piece
};

// A cell's vLOD as pieces, ascending: each object of its set at the level `rule` draws there.
std::vector<PieceId> vlod_pieces(const World& world, const PieceTable& pieces, const ViewCellPartition& partition,
                                 CellId cell, std::span<const ObjectId> set, const CellLodRule& rule);

// From one cell's vLOD to a face neighbour's: to = (from ∪ added) \ removed.
struct VlodDelta {
  std::vector<PieceId> added, removed;
};

// What the section costs, beside the forms vLOD §2.4 compares it with.
struct VlodSizes {
  uint64_t cells = 0, cells_with_vlod = 0, keyframes = 0, face_pairs = 0;
  uint64_t delta_ids = 0, vlod_ids = 0;     // Σ |A| + |R| over the pairs; Σ |vLOD| over the cells
  uint64_t bitmask_bytes = 0;                // each Δ as two bitmasks over every piece
  uint64_t list_bytes = 0;                   // each Δ as plain 32-bit ids
  std::array<uint64_t, std::size(kIdCodecs)> codec_bytes{};  // every Δ in one codec, per codec
  uint64_t delta_bytes = 0;                  // the Δ records as stored (each in its smallest codec)
  uint64_t keyframe_bytes = 0;
  uint64_t section_bytes = 0;
  // §3: R(M) of the matrix whose rows are the pieces each crossing adds (A one way, R the
  // other), in the world file's layout as it was (the builder's object order, unless an earlier
  // run reordered it), in the Morton order of the objects' centres (the seed's
  // baseline) and in the Hamming-TSP order of disk_order.hpp.
  uint64_t runs_world_order = 0, runs_morton_order = 0, runs_tsp_order = 0;
  uint64_t runs_written = 0;  // in the layout the world was written with (DiskLayout)
};

// The orders §3 compares, each a permutation of the pieces (order[k] = the piece at position k).
struct PieceOrders {
  std::vector<uint32_t> file, morton, tsp;
};

// §3 applied: the order the world's encoded levels are laid out in on disk, so the pieces each
// crossing adds lie in few contiguous runs. kKeep leaves the geometry as it is; kMorton lays
// it out along the Morton curve of the objects' centres (the baseline); kTsp in the
// Hamming-TSP order of the Δs' additions (disk_order.hpp). Only the geometry and lods sections
// change: each level's bytes move, its table entry follows them (docs/format.md).
enum class DiskLayout { kKeep, kMorton, kTsp };
std::string disk_layout_name(DiskLayout layout);
std::vector<std::string> disk_layout_names();
// Throws Error listing disk_layout_names() for an unknown name.
DiskLayout parse_disk_layout(const std::string& name);

// Writes `out`: `world` with its vlod section replaced by the one of these sets, every other
// section (the cells, pvs and dov of another run too) kept, so one world serves vlod beside the
// strategies that read DoVs, and its geometry laid out as `layout` says, the section's pieces
// numbered in that layout. Key cells: in id order, a cell with a vLOD and no key cell within
// `key_spacing` face steps becomes one. With `orders`, returns the orders R(M) was measured in
// (pieces numbered as in `world`). Atomic. REQUIRES: every computed cell has a set.
VlodSizes write_world_with_vlod(const World& world, const std::string& out, const ViewCellPartition& partition,
                                const CellSets& sets, const CellLodRule& rule, DiskLayout layout = DiskLayout::kTsp,
                                int key_spacing = 3, PieceOrders* orders = nullptr);

// Reads the section's index (its cells; per cell: key frame and the Δ records of its faces) and reads each
// record from the file when asked. Thread-safety: const methods may be called concurrently.
class StoredVlod {
 public:
  // Throws Error naming the command to run if the world has no vlod section, or on damage.
  explicit StoredVlod(const World& world);
  const ViewCellPartition& partition() const { return *partition_; }
  const CellLodRule& rule() const { return rule_; }
  const PieceTable& pieces() const { return pieces_; }
  bool has_vlod(CellId cell) const { return cells_.at(cell).has_vlod; }
  bool is_key(CellId cell) const { return cells_.at(cell).key_bytes > 0; }
  // The full vLOD of a key cell. REQUIRES is_key(cell).
  std::vector<PieceId> key_vlod(CellId cell) const;
  // The Δ from `from` to its face neighbour `to`; nullopt when they share no stored Δ (one has
  // no vLOD, or they are not face neighbours).
  std::optional<VlodDelta> delta(CellId from, CellId to) const;
  // The face neighbours `cell` has a Δ to.
  std::vector<CellId> neighbours(CellId cell) const;
  // Bytes the reader holds: the index and the partition.
  uint64_t resident_bytes() const;
  // Bytes read from the section so far (key frames and Δ records).
  uint64_t bytes_read() const;

 private:
  struct Face {
    CellId neighbour;
    bool forward;  // the record is stored as this cell → neighbour
    uint64_t offset;
    uint32_t bytes;
  };
  struct Cell {
    bool has_vlod = false;
    uint64_t key_offset = 0;
    uint32_t key_bytes = 0;
    std::vector<Face> faces;
  };
  std::vector<uint8_t> read(uint64_t offset, uint32_t bytes) const;

  const World& world_;
  std::unique_ptr<ViewCellPartition> partition_;
  CellLodRule rule_;
  PieceTable pieces_;
  std::vector<Cell> cells_;
  mutable std::atomic<uint64_t> bytes_read_{0};
};

}  // namespace cellwalk::visibility
