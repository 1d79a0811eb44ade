// The world a `cellwalk bench <name>` measures; see bench_world.hpp.
#include "experiments/common/bench_world.hpp"

#include <filesystem>
#include <functional>
#include <memory>

#include "cellwalk/index/rtree.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "core/progress.hpp"

namespace cellwalk::bench {
namespace {

// Advances a progress line per object on the way into the scene file.
class ProgressSink : public ObjectSink {
 public:
  ProgressSink(ObjectSink& next, Progress& progress) : next_(next), progress_(progress) {}
  void add(const Object& object) override {
    progress_.update(++objects_);
    next_.add(object);
  }

 private:
  ObjectSink& next_;
  Progress& progress_;
  uint64_t objects_ = 0;
};

SceneInfo generate(const GeneratedScene& scene, ObjectSink& sink) {
  if (const auto* city = std::get_if<CityParams>(&scene)) return generate_city(*city, sink);
  if (const auto* city = std::get_if<StratifiedCityParams>(&scene)) return generate_stratified_city(*city, sink);
  return generate_plant(std::get<PlantParams>(scene), sink);
}

}  // namespace

void write_generated_scene(const GeneratedScene& scene, const std::string& scene_file,
                           const std::string& progress_label) {
  SceneWriter writer(scene_file);
  if (progress_label.empty()) {
    writer.finish(generate(scene, writer));
    return;
  }
  const auto* city = std::get_if<CityParams>(&scene);
  Progress progress(progress_label, city ? city->objects : 0);  // a plant's count is not known ahead
  ProgressSink sink(writer, progress);
  SceneInfo info = generate(scene, sink);
  progress.finish();
  writer.finish(std::move(info));
}

BuildReport build_bench_world(const std::string& scene_file, const std::string& world_file, const WorldBuild& build) {
  std::unique_ptr<Progress> progress;  // made at the first call, which brings the object count
  std::function<void(uint64_t, uint64_t)> on_progress;
  if (!build.progress_label.empty())
    on_progress = [&](uint64_t done, uint64_t total) {
      if (!progress) progress = std::make_unique<Progress>(build.progress_label, total);
      progress->update(done);
    };
  ExtraSections rtree;
  if (build.rtree_fanout > 0)
    rtree = [&](WorldWriter& writer, std::span<const Aabb> bounds) {
      const RTreeParams params{.max_entries = build.rtree_fanout};
      write_rtree_section(build_rtree(bounds, params, writer.page_size()), writer);
    };
  const BuildReport report = build_world(scene_file, world_file, build.params, on_progress, rtree);
  if (progress) progress->finish();
  return report;
}

BuildReport make_bench_world(const GeneratedScene& scene, const WorldBuild& build, const std::string& scene_file,
                             const std::string& world_file) {
  write_generated_scene(scene, scene_file);
  const BuildReport report = build_bench_world(scene_file, world_file, build);
  std::filesystem::remove(scene_file);
  return report;
}

}  // namespace cellwalk::bench
