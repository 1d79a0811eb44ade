// make_strategy: the one place that knows every strategy by name.
#include "cellwalk/core/error.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/systems/visual/visual_strategy.hpp"
#include "cellwalk/systems/review/review.hpp"
#include "cellwalk/systems/vlod/vlod_strategy.hpp"
#include "cellwalk/systems/stratified/stratified_strategy.hpp"
#include "cellwalk/systems/lichiang/lichiang_strategy.hpp"
#include "cellwalk/systems/pvs_stream_client/pvs_stream_strategy.hpp"
#include "cellwalk/systems/vdr_client/vdr_strategy.hpp"
#include "cellwalk/strategy/strategy.hpp"
#include "systems/brute/brute.hpp"
#include "systems/scene_tree/scene_tree_strategy.hpp"

namespace cellwalk {

std::vector<std::string> strategy_names() {
  return {"brute", "ground-truth", "lod[:px=P]", "conv", "hdov-vsc", "hdov-pb", "review[-nc|-np|-box][:key=value,...]", "visual[:key=value,...]",
          "vlod[:key=value,...]", "stratified[:key=value,...]",
          "lichiang[:key=value,...]", "pvs-stream[:key=value,...]", "vdr[:key=value,...]"};
}

namespace {

[[noreturn]] void unknown_strategy(const std::string& name) {
  std::string known;
  for (const auto& n : strategy_names()) known += (known.empty() ? "" : ", ") + n;
  fail("strategy \"" + name + "\"", "unknown; choose one of " + known);
}

}  // namespace

void check_strategy_name(const std::string& name) {
  for (const char* plain : {"brute", "ground-truth", "conv", "hdov-vsc", "hdov-pb"})
    if (name == plain) return;
  if (is_lod_strategy_name(name)) return void(parse_lod_strategy_name(name));
  if (is_review_strategy_name(name)) return void(parse_review_strategy_name(name));
  if (is_visual_strategy_name(name)) return void(parse_visual_strategy_name(name));
  if (is_vlod_strategy_name(name)) return void(parse_vlod_strategy_name(name));
  if (is_stratified_strategy_name(name)) return void(parse_stratified_strategy_name(name));
  if (is_lichiang_strategy_name(name)) return void(parse_lichiang_strategy_name(name));
  if (is_pvs_stream_strategy_name(name)) return void(parse_pvs_stream_strategy_name(name));
  if (is_vdr_strategy_name(name)) return void(parse_vdr_strategy_name(name));
  unknown_strategy(name);
}

std::unique_ptr<Strategy> make_strategy(const std::string& name, const World& world,
                                        const StrategyOptions& options) {
  if (name == "brute") return std::make_unique<BruteStrategy>(world, options, true);
  if (name == "ground-truth") return std::make_unique<BruteStrategy>(world, options, false);
  if (is_lod_strategy_name(name)) return std::make_unique<BruteStrategy>(world, options, true, parse_lod_strategy_name(name));
  if (name == "conv") return std::make_unique<SceneTreeStrategy>(world, options, SceneTreeStrategy::Traversal::kConv);
  if (name == "hdov-vsc") return std::make_unique<SceneTreeStrategy>(world, options, SceneTreeStrategy::Traversal::kVsc);
  if (is_review_strategy_name(name)) return std::make_unique<ReviewStrategy>(world, parse_review_strategy_name(name), options);
  if (is_visual_strategy_name(name)) return std::make_unique<VisualStrategy>(world, parse_visual_strategy_name(name), options);
  if (is_vlod_strategy_name(name)) return std::make_unique<VlodStrategy>(world, parse_vlod_strategy_name(name), options);
  if (is_stratified_strategy_name(name))
    return std::make_unique<StratifiedStrategy>(world, parse_stratified_strategy_name(name), options);
  if (is_lichiang_strategy_name(name))
    return std::make_unique<LiChiangStrategy>(world, parse_lichiang_strategy_name(name), options);
  if (is_pvs_stream_strategy_name(name))
    return std::make_unique<PvsStreamStrategy>(world, parse_pvs_stream_strategy_name(name), options);
  if (is_vdr_strategy_name(name)) return std::make_unique<VdrStrategy>(world, parse_vdr_strategy_name(name), options);
  if (name == "hdov-pb") return std::make_unique<SceneTreeStrategy>(world, options, SceneTreeStrategy::Traversal::kPb);
  unknown_strategy(name);
}

}  // namespace cellwalk
