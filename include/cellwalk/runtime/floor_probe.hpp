// The floor under a walker (issue 16, item 4): the viewer keeps its eye at eye height above the
// surface under it, so it climbs a stair, stands on a roof it walked onto and drops off a ledge,
// instead of keeping one height over the world's lowest point.
#pragma once

#include <cstdint>
#include <list>
#include <optional>
#include <utility>
#include <unordered_map>

#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

class FloorProbe {
 public:
  // Each object is probed at its coarsest level whose object-space error is at most
  // `tolerance` (metres): floors come out within it. The meshes read are kept, least recently
  // used first out, within `cache_bytes` (all the probe adds to the process: a mesh larger than
  // that alone is not probed, and skipped() counts it).
  FloorProbe(const World& world, float tolerance, uint64_t cache_bytes);

  // The height of the highest surface that a vertical ray from `from` meets going down: the
  // y of the highest triangle whose projection on the ground plane holds (from.x, from.z), at or
  // below from.y; the world's lowest point when there is none. The candidates are every object
  // whose bounds hold the column below `from`. The same `from` twice is answered without
  // probing again. Not thread-safe (the cache).
  float floor_below(const Vec3& from);

  uint64_t cached_bytes() const { return cached_bytes_; }
  uint64_t skipped() const { return skipped_; }

 private:
  const Mesh* mesh(ObjectId id);

  const World& world_;
  float tolerance_;
  uint64_t cache_bytes_, cached_bytes_ = 0, skipped_ = 0;
  std::optional<std::pair<Vec3, float>> last_;  // the last query and its answer
  std::list<ObjectId> order_;  // most recently used first
  struct Entry {
    Mesh mesh;
    std::list<ObjectId>::iterator at;
  };
  std::unordered_map<ObjectId, Entry> cache_;
};

// The y of the highest triangle of `mesh` below `from` on the vertical through it, or -inf.
// A column on an edge shared by two triangles meets both (a small tolerance), so a walker on
// a roof's diagonal does not fall through it.
float highest_surface_below(const Mesh& mesh, const Vec3& from);

}  // namespace cellwalk
