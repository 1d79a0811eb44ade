// The seam every walkthrough system plugs into. A strategy chooses, per frame, what to draw
// (objects and levels of detail) and supplies their geometry through its own storage; the
// walk harness renders and measures every strategy the same way.
#pragma once

#include <utility>

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/core/camera.hpp"
#include "cellwalk/strategy/frame_stats.hpp"
#include "cellwalk/render/renderer.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

// What a strategy's index queries have cost over its life (REVIEW's searches, VISUAL's cell-change
// searches): for reports that hold systems side by side without knowing their types.
struct QueryTotals {
  uint64_t queries = 0;
  uint64_t disk_ios = 0;  // page reads of the index and visibility data, as the system counts them
  double ms = 0.0;        // the queries' own time (search, and the I/O and decode they did)
};

class Strategy {
 public:
  virtual ~Strategy() = default;
  virtual std::string name() const = 0;

  // Replaces `items` with what to draw from `camera`. Adds query time (and any I/O it does)
  // to `stats`. On entry stats.time is the frame's path time when the caller has one (walk,
  // compare), else 0.
  virtual void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) = 0;

  // The geometry of an item the renderer does not hold. The pointer stays valid until the
  // next call. Adds I/O and decode time, bytes read, hits and misses to `stats`. nullptr means
  // the data is not available this frame (the frame then counts as a stall).
  virtual const Mesh* mesh(const DrawItem& item, FrameStats& stats) = 0;

  // True when mesh() gives any level of any object (it reads through a GeometryStore, with no
  // bookkeeping of what was drawn), so a view may draw an object at another level than selected:
  // the viewer's bird's-eye view draws the chosen set coarser, as seen from far above.
  virtual bool serves_every_level() const { return false; }

  // The far faces (stratified rendering) the last select() chose, drawn as background under the
  // items; their images stay valid until the next select(). Empty for every other strategy.
  virtual std::span<const FarFace> far_faces() const { return {}; }

  // Lines a viewer's bird's-eye view draws to show the system's own structure around the last
  // select() (stratified: the viewcell and its bounding box). None by default.
  virtual void overlay(std::vector<LineSegment>& lines) const { (void)lines; }

  // Bytes the strategy holds in memory now (geometry, index, visibility data): what its memory
  // budget bounds.
  virtual uint64_t resident_bytes() const = 0;
  // The largest resident_bytes() has been, exactly (not sampled per frame).
  virtual uint64_t peak_resident_bytes() const = 0;
  // Zero for strategies that run no index queries.
  virtual QueryTotals query_totals() const { return {}; }
  // The strategy's own counters for a walk's report, name → value (a streaming client's
  // transactions, bytes received, frames drawn late); none by default.
  virtual std::vector<std::pair<std::string, double>> walk_counters() const { return {}; }
};

struct StrategyOptions {
  uint64_t memory_budget_bytes = 0;  // 0 = unbounded; never exceeded
  // The height of the images drawn, pixels (0: unknown). vlod refuses images whose pixels
  // would magnify its levels' error past the bound they were chosen for.
  float viewport_height_px = 0.0f;
  // HDoV thesis η: the DoV threshold of the threshold searches (hdov-vsc; docs/scene-tree.md).
  double eta = 0.001;
  // hdov-pb: the polygon budget, triangles per frame (HDoV thesis §6.1.2).
  uint64_t polygon_budget = 20000;
  // hdov-vsc, hdov-pb: lower objects' levels by their DoV (eq. 5.6, PB's λ). false: VSC draws
  // visible objects at level 0 and PB's levels follow its budget shares alone.
  bool dov_levels = true;
  // hdov-vsc, hdov-pb, conv: the k-d scene tree file ("" = WORLD.scenetree, built on first use).
  std::string scene_tree_file;
  // Where every strategy's geometry store reads levels from: "" = the world file; otherwise an
  // object database built from the world (`cellwalk db`, store/object_database.hpp), its cache
  // charged to memory_budget_bytes.
  std::string objects_db;
};

}  // namespace cellwalk
