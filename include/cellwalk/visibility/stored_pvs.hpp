// The stored visible sets of a world (sections "cells", "pvs", "dov"; docs/format.md,
// "Visibility sections"): the writer the precompute ends with, and the reader every run-time
// consumer uses. Depends on the store only (no Embree, no GL), so a server can serve sets.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/store/world.hpp"
#include "cellwalk/store/world_file.hpp"
#include "cellwalk/visibility/view_cell.hpp"
#include "cellwalk/visibility/visibility.hpp"

namespace cellwalk::visibility {

inline constexpr const char* kCellsSection = "cells";
inline constexpr const char* kPvsSection = "pvs";
inline constexpr const char* kDovSection = "dov";

// The sets of one run, by cell (solid, skipped and not-yet-computed cells absent).
using CellSets = std::map<CellId, VisibleSet>;

struct PvsRun {
  std::string engine;           // its name, stored with the sets
  bool conservative = false;
  std::string settings;         // everything else that changes the result (cells spec, options)
  int shard = 0;                // this run computes shard `shard` of `shards` equal id ranges
  int shards = 1;
  int threads = 0;              // 0: all cores
};

// What storing the sets costs.
struct PvsSizes {
  uint64_t cells = 0;
  uint64_t cells_with_sets = 0;
  uint64_t ids = 0;               // Σ set sizes
  uint64_t bitmask_bytes = 0;     // one bitmask per cell with a set
  uint64_t full_bytes = 0;        // every set gap-coded on its own
  uint64_t stored_bytes = 0;      // the "pvs" records as stored (gaps, bitmask or Δ, the smallest)
  uint64_t delta_cells = 0;       // cells stored as a Δ
  uint64_t face_pairs = 0;        // face-adjacent pairs of cells with sets
  uint64_t face_delta_bytes = 0;  // Σ over those pairs of the coded Δ (vLOD's per-face storage)
  uint64_t dov_bytes = 0;
};

// Writes `out`: every section of `world` except old visibility sections, then "cells", "pvs"
// and, if the sets carry DoVs, "dov". Atomic: nothing appears at `out` until it is complete, so
// `out` may be the world's own path. REQUIRES: every cell that is neither solid nor skipped
// has a set.
PvsSizes write_world_with_pvs(const World& world, const std::string& out, const ViewCellPartition& partition,
                              const CellSets& sets, const PvsRun& run);

// A section to write: its bytes, or, for one too large to hold (a world's geometry), a
// function that writes them into the open section.
struct NamedSection {
  std::string name;
  std::vector<uint8_t> bytes;
  std::function<void(WorldWriter&)> stream;
};
// Writes `out`: every section of `world` but those named in `drop` or in `sections`, then
// `sections`. Atomic, as above.
void write_world_sections(const World& world, const std::string& out, const std::vector<NamedSection>& sections,
                          const std::vector<std::string>& drop = {});

// Reads the visibility sections of a world. Thread-safety: const methods may be called
// concurrently.
class StoredPvs {
 public:
  // Throws Error if the world has no "cells"/"pvs" sections or they are damaged.
  explicit StoredPvs(const World& world);
  const ViewCellPartition& partition() const { return *partition_; }
  const std::string& engine() const { return engine_; }
  bool conservative() const { return conservative_; }
  bool has_dov() const { return !dov_.empty(); }
  // The set of a cell (with DoVs when stored); nullopt for solid cells. Throws Error for a
  // skipped cell (no set was computed: callers check partition().cell(c).skipped first).
  std::optional<VisibleSet> set(CellId cell) const;
  // Bytes the reader holds: the sections as read, their offsets and the partition.
  uint64_t resident_bytes() const;

 private:
  std::span<const uint8_t> record(CellId cell) const;
  std::vector<ObjectId> decode(CellId cell, int depth) const;

  std::unique_ptr<ViewCellPartition> partition_;
  std::string engine_;
  bool conservative_ = false;
  uint64_t object_count_ = 0;
  std::vector<uint8_t> pvs_;
  std::vector<uint64_t> offsets_;  // cell_count + 1, into pvs_
  std::vector<uint8_t> dov_;
  std::vector<uint64_t> dov_offsets_;
};

}  // namespace cellwalk::visibility
