// Precomputing visible sets for every view cell of a world: parallel over cells, resumable
// from a checkpoint, splittable by cell range (--shard i/N) and merged. How the sets are stored
// and read back: cellwalk/visibility/stored_pvs.hpp.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "precompute/embree_scene.hpp"

namespace cellwalk::visibility {

// Builds the partition a spec names: "grid:SIZE" (2D at eye height), "grid3d:SIZE",
// "kd:SIZE", "octree[:ROOT[:THRESHOLD[:DEPTH]]]" (THRESHOLD in triangles of the visible set:
// `set_size` when given, else level-0 triangles of what a light sampling engine sees). Cells
// inside objects are marked solid. Throws Error on a malformed spec.
std::unique_ptr<ViewCellPartition> make_partition(const std::string& spec, const World& world,
                                                  const EmbreeScene& scene, const CellSetSize& set_size = {});

// vLOD §2.1's measure of a candidate cell: the triangles of its vLOD, i.e. of the levels `rule`
// draws of the objects `engine` keeps. The engine and the world must outlive the result.
CellSetSize drawn_triangles(const VisibilityEngine& engine, const World& world, const CellLodRule& rule);

// `partition` with every cell farther than `margin` metres from the camera path skipped: a
// cell is kept when the path's polyline (frame to frame) meets its box grown by `margin` on
// every side (so corners reach up to margin·√3). Throws Error for a path with no frames or a
// margin that is negative or not finite.
std::unique_ptr<ViewCellPartition> cells_along(const ViewCellPartition& partition, const CameraPath& path, float margin);

// The identity of a run: the engine and everything else that changes its sets (the cells spec
// and the engine's options), stored in checkpoints and part files so a resumed or merged run
// is the same run. `shard` is "" (the whole partition) or "i/N". Throws Error on a bad shard.
PvsRun make_pvs_run(const VisibilityEngine& engine, const std::string& cells_spec, const EngineOptions& options,
                    const std::string& shard = "", int threads = 0);

// "i/N" exactly: two whole numbers, 0 <= i < N, nothing before or after. Throws Error naming
// --shard otherwise.
void parse_shard(const std::string& text, int& shard, int& shards);

// The cells to compute (neither solid nor skipped) of shard `shard` of `shards`: ids in [shard·C/shards, (shard+1)·C/shards).
std::vector<CellId> shard_cells(const ViewCellPartition& partition, int shard, int shards);

// Computes the sets of the run's cells in parallel, appending each to `checkpoint` as it
// completes (created if missing; its valid records are reused, so a killed run resumes where it
// stopped). Throws Error if the checkpoint belongs to a different run (world, cells, settings
// or shard). `progress` is called with (cells done, cells total) from one thread at a time.
// Returns every set of the shard, resumed and new.
CellSets compute_cell_sets(const World& world, const VisibilityEngine& engine,
                           const ViewCellPartition& partition, const PvsRun& run,
                           const std::string& checkpoint,
                           const std::function<void(uint64_t, uint64_t)>& progress = {});

// A shard's result file is its completed checkpoint. Reads one (checking it against nothing but
// itself) and returns its partition, run and sets.
struct PvsPart {
  std::unique_ptr<ViewCellPartition> partition;
  PvsRun run;
  uint64_t run_hash = 0;
  CellSets sets;
};
PvsPart read_pvs_part(const std::string& path, const World& world);

// The part files of every shard of one run, merged. Throws Error naming a part of a different
// run (partition, engine, settings or shard count) or one that repeats a shard.
struct PvsMerge {
  std::unique_ptr<ViewCellPartition> partition;
  PvsRun run;
  CellSets sets;
};
PvsMerge merge_pvs_parts(const std::vector<std::string>& paths, const World& world);

}  // namespace cellwalk::visibility
