#include "strategy/brute.hpp"

#include "core/stopwatch.hpp"

namespace cellwalk {

BruteStrategy::BruteStrategy(const SceneReader& scene, bool cull) : scene_(scene), cull_(cull) {}

void BruteStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Stopwatch watch;
  items.clear();
  const Frustum frustum(camera);
  for (ObjectId id = 0; id < scene_.object_count(); ++id) {
    const SceneEntry& e = scene_.entry(id);
    if (!cull_ || frustum.intersects(e.bounds)) items.push_back({id, 0, e.color});
  }
  stats.query_ms += watch.ms();
}

const Mesh* BruteStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  Stopwatch watch;
  auto record = scene_.read_record(item.object);
  stats.io_ms += watch.lap_ms();
  stats.bytes_read += record.size();
  ++stats.cache_misses;
  current_ = scene_.decode_record(item.object, record);
  stats.decode_ms += watch.lap_ms();
  return &current_->mesh;
}

uint64_t BruteStrategy::resident_bytes() const { return current_ ? current_->mesh.byte_size() : 0; }

}  // namespace cellwalk
