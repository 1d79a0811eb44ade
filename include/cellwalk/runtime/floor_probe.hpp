// The floor under a walker (issue 16, item 4): the viewer keeps its eye at eye height above the
// surface under it, so it climbs a stair, stands on a roof it walked onto and drops off a ledge,
// instead of keeping one height over the world's lowest point.
#pragma once

#include <cstdint>
#include <list>
#include <unordered_map>

#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {

class FloorProbe {
 public:
  // Level-0 meshes read for probing are kept, least recently used first out, within
  // `cache_bytes` (what the probe adds to the process; a larger mesh is read for each probe).
  FloorProbe(const World& world, uint64_t cache_bytes);

  // The height of the highest surface that a vertical ray from `from` meets going down: the
  // y of the first triangle (of any object's level 0) whose projection on the ground plane
  // holds (from.x, from.z) at or below from.y; the world's lowest point when there is none.
  // Exact: the candidates are every object whose bounds hold the column below `from`.
  // Not thread-safe (the cache).
  float floor_below(const Vec3& from);

  uint64_t cached_bytes() const { return cached_bytes_; }

 private:
  const Mesh& mesh(ObjectId id, Mesh& uncached);

  const World& world_;
  uint64_t cache_bytes_, cached_bytes_ = 0;
  std::list<ObjectId> order_;  // most recently used first
  struct Entry {
    Mesh mesh;
    std::list<ObjectId>::iterator at;
  };
  std::unordered_map<ObjectId, Entry> cache_;
};

// The y of the highest triangle of `mesh` below `from` on the vertical through it, or -inf.
float highest_surface_below(const Mesh& mesh, const Vec3& from);

}  // namespace cellwalk
