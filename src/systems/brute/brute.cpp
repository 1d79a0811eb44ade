#include "systems/brute/brute.hpp"

#include "cellwalk/core/error.hpp"
#include "cellwalk/lod/screen_error.hpp"
#include "cellwalk/store/level_choice.hpp"
#include "core/stopwatch.hpp"
#include "strategy/strategy_config.hpp"

namespace cellwalk {

bool is_lod_strategy_name(const std::string& name) { return name == "lod" || name.rfind("lod:", 0) == 0; }

LodBaselineConfig parse_lod_strategy_name(const std::string& name) {
  if (!is_lod_strategy_name(name)) fail("strategy \"" + name + "\"", "not a lod name (lod[:px=P])");
  LodBaselineConfig c;
  for_each_strategy_setting(name, [&](const StrategySetting& s) {
    if (s.key == "px") c.max_px = static_cast<float>(s.number(1e-3, 1e3));
    else s.unknown("px");
  });
  return c;
}

BruteStrategy::BruteStrategy(const World& world, const StrategyOptions& options, bool cull,
                             std::optional<LodBaselineConfig> lod)
    : world_(world),
      store_(world, options.memory_budget_bytes, nullptr, 1, open_level_source(world, options.objects_db)),
      cull_(cull || lod),
      lod_(lod),
      viewport_height_px_(options.viewport_height_px) {
  if (lod_ && !(viewport_height_px_ > 0.0f))
    fail("strategy lod", "needs the image height to measure screen-space error; run it from walk, compare, render or view");
}

void BruteStrategy::select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) {
  Stopwatch watch;
  items.clear();
  const Frustum frustum(camera);
  const Lens lens = lens_of(camera, viewport_height_px_);
  for (ObjectId id = 0; id < world_.object_count(); ++id) {
    const ObjectRecord& o = world_.object(id);
    if (cull_ && !frustum.intersects(o.bounds)) continue;
    const uint32_t level = lod_ ? level_for_screen_error(world_, id, camera.position, lens, lod_->max_px) : 0;
    items.push_back({id, level, o.color});
  }
  stats.query_ms += watch.ms();
}

const Mesh* BruteStrategy::mesh(const DrawItem& item, FrameStats& stats) {
  current_.reset();  // the renderer has uploaded it: let the store evict it
  current_ = store_.get(item.id, item.lod, EntryMeta{}, stats);
  return current_.get();
}

}  // namespace cellwalk
