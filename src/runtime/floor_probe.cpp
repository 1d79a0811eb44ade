// The floor under a walker (floor_probe.hpp): a vertical ray cast down through the level-0
// triangles of the objects whose bounds hold the column, on the CPU, so the viewer needs neither
// Embree nor the whole world in memory.
#include "cellwalk/runtime/floor_probe.hpp"

#include <cmath>
#include <limits>

namespace cellwalk {

float highest_surface_below(const Mesh& mesh, const Vec3& from) {
  float best = -std::numeric_limits<float>::infinity();
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const Vec3& a = mesh.positions[mesh.indices[t]];
    const Vec3& b = mesh.positions[mesh.indices[t + 1]];
    const Vec3& c = mesh.positions[mesh.indices[t + 2]];
    // Barycentric coordinates of (x, z) in the triangle's ground-plane projection; a wall's
    // projection has no area and holds no column.
    const float area = (b.x - a.x) * (c.z - a.z) - (c.x - a.x) * (b.z - a.z);
    if (std::abs(area) < 1e-12f) continue;
    const float u = ((b.x - from.x) * (c.z - from.z) - (c.x - from.x) * (b.z - from.z)) / area;
    const float v = ((c.x - from.x) * (a.z - from.z) - (a.x - from.x) * (c.z - from.z)) / area;
    const float w = 1.0f - u - v;
    constexpr float kOnEdge = -1e-5f;
    if (u < kOnEdge || v < kOnEdge || w < kOnEdge) continue;
    const float y = u * a.y + v * b.y + w * c.y;
    if (y <= from.y && y > best) best = y;
  }
  return best;
}

namespace {

// What a cache entry holds beyond its arrays (map node, list node, vector headers).
constexpr uint64_t kEntryOverheadBytes = 160;

}  // namespace

FloorProbe::FloorProbe(const World& world, float tolerance, uint64_t cache_bytes)
    : world_(world), tolerance_(tolerance), cache_bytes_(cache_bytes) {}

const Mesh* FloorProbe::mesh(ObjectId id) {
  if (auto it = cache_.find(id); it != cache_.end()) {
    order_.splice(order_.begin(), order_, it->second.at);
    return &it->second.mesh;
  }
  const ObjectRecord& o = world_.object(id);
  uint32_t level = 0;
  while (level + 1 < o.lod_count && world_.lod(id, level + 1).error <= tolerance_) ++level;
  // Positions and indices only, as the decoded mesh will hold them: one larger than the whole
  // cache is not read at all.
  const LodRecord& lod = world_.lod(id, level);
  if (uint64_t(lod.triangles) * 3 * sizeof(uint32_t) + kEntryOverheadBytes > cache_bytes_) {
    ++skipped_;
    return nullptr;
  }
  Mesh m = world_.decode_level(id, level, world_.read_level(id, level));
  m.normals = {};
  m.colors = {};
  const uint64_t bytes = m.byte_size() + kEntryOverheadBytes;
  if (bytes > cache_bytes_) {
    ++skipped_;
    return nullptr;
  }
  while (cached_bytes_ + bytes > cache_bytes_) {
    const auto last = cache_.find(order_.back());
    cached_bytes_ -= last->second.mesh.byte_size() + kEntryOverheadBytes;
    cache_.erase(last);
    order_.pop_back();
  }
  order_.push_front(id);
  cached_bytes_ += bytes;
  return &cache_.emplace(id, Entry{std::move(m), order_.begin()}).first->second.mesh;
}

float FloorProbe::floor_below(const Vec3& from) {
  if (last_ && last_->first == from) return last_->second;
  float floor = -std::numeric_limits<float>::infinity();
  for (ObjectId id = 0; id < world_.object_count(); ++id) {
    const Aabb& box = world_.object(id).bounds;
    if (from.x < box.min.x || from.x > box.max.x || from.z < box.min.z || from.z > box.max.z || box.min.y > from.y ||
        box.max.y <= floor)
      continue;
    if (const Mesh* m = mesh(id)) floor = std::max(floor, highest_surface_below(*m, from));
  }
  if (std::isinf(floor)) floor = world_.info().bounds.min.y;
  last_ = {from, floor};
  return floor;
}

}  // namespace cellwalk
