// The conservative from-region visibility engine: never drops an object visible from any point
// of the view cell (the guarantee, its proof and its limits: docs/conservative-visibility.md).
// Seeds: 001 vLOD §5.2 (occluder shrinking, rendered from one point of the cell into a depth
// buffer with conservative rasterisation) and 000 HDoV thesis §5.5.1 (a convex occluder that
// hides an object from the cell's 8 corners hides it from the whole box cell).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>

#include "cellwalk/precompute/engine.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

struct ConservativeParams {
  // Pixels per side of each of the 6 faces of the cube depth buffer around the cell. A pixel
  // is covered only when one shrunk occluder covers all of it, so a building far away covers
  // no pixel once it is narrower than one: at 64² (up to 1.8° per pixel) that is a 15 m
  // building beyond ~500 m, and the far field showed through every pixel two buildings shared
  // (10⁷-triangle city: sets 8.8× the ground truth; 3.6× at 256², at ~1.15× the time, since
  // the culling renders only pixels candidates need; docs/conservative-visibility.md).
  int face_resolution = 256;
  // Voxels along the longest side of an object's box when its inscribed occluder boxes are
  // derived (the solid is classified on this grid).
  int occluder_grid = 24;
  // At most this many inscribed boxes per object; each further box must add at least
  // min_box_gain of the object's interior voxels not covered by the earlier ones.
  int max_boxes_per_object = 3;
  double min_box_gain = 0.15;
  // vLOD §5.2: occluders shrunk by the cell, rendered from the cell's centre (with fusion).
  bool occluder_shrinking = true;
  // HDoV §5.5.1: one unshrunk occluder hides the object from all 8 cell corners (no fusion,
  // but thin and small occluders count).
  bool corner_test = true;
  // Occluders standing on the floor (the lowest point of any object) reach down without end:
  // nothing lies below the floor, so no segment from a viewpoint above it passes underneath.
  // Keeps shrinking by the cell's height from opening a gap at the ground.
  bool grounded_occluders = true;
  // The cell is refined this many times (split in half along every axis at least half as
  // long as its longest: x and z for a flat eye-height cell); an object is dropped only if
  // every leaf it reaches hides it. Shrinking loses the size of the region at every occluder
  // edge, so smaller regions hide much more; the union keeps the guarantee.
  int refine_levels = 3;
  // Only occluders within this distance of the cell take part in the corner test (metres).
  double corner_test_radius = 200.0;
  // Threads deriving the occluders when the engine is made; 0 = all cores.
  int threads = 0;
  // Occluders from the world's surfaces, however it is split into objects (issue 15,
  // docs/surface-occluders.md): openings at least smallest_hole wide (metres) stay open;
  // boxes thinner than smallest_occluder in their two longer edges are dropped. 0: off.
  // Holds for level 0 only, so not with occluder_margin.
  double smallest_hole = 0.0;
  double smallest_occluder = 1.0;
  // vLOD §4: visibility computed on the levels drawn from the cell. The occluder boxes are
  // inscribed in level 0; a level whose surface lies within e of level 0 still holds each box
  // eroded by e, so every box of `object` is eroded by occluder_margin(cell, object) metres
  // (the error of the level drawn from that cell) before it hides anything. Empty: 0 (level 0).
  std::function<float(const Aabb& cell, ObjectId object)> occluder_margin;
};

// What the engine derived from the world, for reports.
struct ConservativeStats {
  uint64_t objects = 0;
  uint64_t closed_objects = 0;    // meshes with no boundary edge: candidates for occluders
  uint64_t occluder_objects = 0;  // objects with at least one inscribed box
  uint64_t occluder_boxes = 0;    // inscribed boxes
  uint64_t bridges = 0;           // boxes across two touching inscribed boxes
  double mean_fill = 0.0;         // mean over objects of largest box volume / object box volume
  double occluder_seconds = 0.0;  // to decode the meshes and derive the boxes
  // The surface source (ConservativeParams::smallest_hole > 0); zero when off.
  double voxel_edge = 0.0;            // metres
  uint64_t voxels = 0;
  uint64_t surface_voxels = 0;        // voxels a triangle meets
  uint64_t free_components = 0;       // 26-connected components of the other voxels
  uint64_t surface_boxes = 0;         // occluder boxes from them (part of occluder_boxes)
};

// Derives every object's occluders from level 0 of the world (decoded, so they are exact for
// the geometry that is drawn) and returns the engine. The world must outlive the engine.
// compute(cell) returns the objects not proven hidden from the whole cell, ascending, no
// DoV; a solid cell (no viewer can stand there) gives the empty set.
std::unique_ptr<VisibilityEngine> make_conservative_engine(const World& world,
                                                           const ConservativeParams& params);

// The stats of an engine make_conservative_engine returned; nullptr for any other engine.
const ConservativeStats* conservative_stats(const VisibilityEngine& engine);

}  // namespace cellwalk
