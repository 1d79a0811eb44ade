#include "systems/brute/brute.hpp"

#include "core/stopwatch.hpp"

namespace cellwalk {

BruteStrategy::BruteStrategy(const World& world, const StrategyOptions& options, bool cull)
    : world_(world), store_(world, options.memory_budget_bytes, nullptr, 1, open_level_source(world, options.objects_db)), cull_(cull) {}

void BruteStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Stopwatch watch;
  items.clear();
  const Frustum frustum(camera);
  for (ObjectId id = 0; id < world_.object_count(); ++id) {
    const ObjectRecord& o = world_.object(id);
    if (!cull_ || frustum.intersects(o.bounds)) items.push_back({id, 0, o.color});
  }
  stats.query_ms += watch.ms();
}

const Mesh* BruteStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  current_.reset();  // the renderer has uploaded it: let the store evict it
  current_ = store_.get(item.id, item.lod, EntryMeta{}, stats);
  return current_.get();
}

}  // namespace cellwalk
