// Visibility engines: compute a view cell's visible set (and degrees of visibility) offline.
// Sampling and DoV cast Embree rays or render cube maps; the conservative engine fuses
// occluders in a depth buffer (docs/visibility.md, docs/conservative-visibility.md).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cellwalk/store/world.hpp"
#include "cellwalk/visibility/cell_lod.hpp"
#include "cellwalk/visibility/view_cell.hpp"
#include "cellwalk/visibility/visibility.hpp"

namespace cellwalk {

// Thread-safety: compute() may be called concurrently for different cells.
class VisibilityEngine {
 public:
  virtual ~VisibilityEngine() = default;
  virtual std::string name() const = 0;
  // True if the engine never drops an object visible from some point of the cell.
  virtual bool conservative() const = 0;
  virtual VisibleSet compute(const ViewCell& cell) const = 0;
};

// ---- Engines that exist (src/precompute/engine_registry.cpp) --------------------------------

// How the DoV engine makes its ID cube maps (docs/visibility.md, "DoV cube maps"): `exact`
// renders every object at level 0 through GL, the reference; `rays` casts one Embree ray per
// pixel centre over the same level-0 meshes, equal to exact within the silhouette tolerance.
enum class DovCubes { kRays, kExact };

// "rays", "exact".
std::string dov_cubes_name(DovCubes cubes);
std::vector<std::string> dov_cubes_names();
// Throws Error listing dov_cubes_names() for an unknown name.
DovCubes parse_dov_cubes(const std::string& name);

struct EngineOptions {
  // Sampling: rays are cast from corners, face centres, the centre and this many random points
  // on the faces and inside, each over this many directions spread over the whole sphere.
  int sample_points = 64;
  int rays_per_point = 4096;
  // Sampling: besides the sphere, this many rays from each point at random points of every
  // object's bounding box. Uniform directions are ~3° apart at 4096 rays, so small distant
  // objects fall between them; aimed rays find those at a cost linear in the object count.
  int aimed_rays_per_object = 4;
  uint64_t seed = 1;
  // DoV: cube-map face resolution (pixels per side) at each of the cell's 8 corners.
  int dov_resolution = 256;
  // DoV: eq. 5.11 at pixel centres as the thesis writes it (its weights sum to 1 - O(1/R²)),
  // instead of the default, eq. 5.11 integrated over each pixel (weights sum to exactly 1).
  bool dov_midpoint_weights = false;
  // DoV: where the cube maps come from (the result differs from exact's only within the
  // tolerance DovEngine/DovCubesAgainstExact states; the mode is part of a run's identity).
  DovCubes dov_cubes = DovCubes::kRays;
  // Conservative: how many times each cell is refined (halved along its long axes) for
  // occluder shrinking; more levels hide more and cost more (docs/conservative-visibility.md).
  int refine_levels = 3;
  // Conservative: occluders from the world's surfaces (docs/surface-occluders.md): openings
  // at least this wide (metres) stay open; 0 leaves the source off. Boxes thinner than
  // smallest_occluder (metres) in their two longer edges are dropped.
  double smallest_hole = 0.0;
  double smallest_occluder = 1.0;
  // vLOD: the levels drawn from each cell (vLOD §2.2), on which its visibility is computed.
  visibility::CellLodRule lod_rule;
};

// Names accepted by make_engine(), e.g. {"sampling", "dov"}.
std::vector<std::string> engine_names();
// Throws Error listing engine_names() for an unknown name. The engine keeps a reference to
// `world`, which must outlive it.
std::unique_ptr<VisibilityEngine> make_engine(const std::string& name, const World& world,
                                              const EngineOptions& options = {});

}  // namespace cellwalk
