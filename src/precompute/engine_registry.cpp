// The visibility engines cellwalk has, by name (issue 4): "sampling" (Embree rays, vLOD §5 as
// sampling), "dov" (HDoV thesis §5.5.2 cube maps, with sampling as its step 1 so objects that
// cover no pixel still get DoV_s) and "conservative" (vLOD §5.2 / HDoV §5.5.1, its own file).
#include <array>
#include <memory>
#include <utility>

#include "cellwalk/precompute/conservative_visibility.hpp"
#include "cellwalk/core/error.hpp"
#include "precompute/dov_engine.hpp"
#include "precompute/sampling_engine.hpp"

namespace cellwalk {

namespace {

// DoV with its step-1 engine owned beside it; both cast rays into one Embree scene.
class DovWithPrior : public VisibilityEngine {
 public:
  DovWithPrior(const World& world, const EngineOptions& options)
      : scene_(std::make_shared<const visibility::EmbreeScene>(world)),
        prior_(world, options, scene_),
        dov_(world, options, &prior_, scene_) {}
  std::string name() const override { return dov_.name(); }
  bool conservative() const override { return false; }
  VisibleSet compute(const ViewCell& cell) const override { return dov_.compute(cell); }

 private:
  std::shared_ptr<const visibility::EmbreeScene> scene_;
  visibility::SamplingEngine prior_;
  visibility::DovEngine dov_;
};

// vLOD(C) (seed 001 §2.3): the objects not proven hidden from the cell when every occluder is
// the level the cell draws of it (§4). Its name carries the level rule, so the stored sets say
// which levels the run time must draw and a run with another rule is another run.
class VlodEngine : public VisibilityEngine {
 public:
  VlodEngine(const World& world, const EngineOptions& options) : rule_(options.lod_rule) {
    ConservativeParams params;
    params.refine_levels = options.refine_levels;
    params.occluder_margin = [&world, rule = rule_](const Aabb& cell, ObjectId id) {
      return world.lod(id, visibility::cell_level(world, id, cell, rule)).error;
    };
    inner_ = make_conservative_engine(world, params);
  }
  std::string name() const override { return "vlod:" + visibility::to_string(rule_); }
  bool conservative() const override { return true; }
  VisibleSet compute(const ViewCell& cell) const override { return inner_->compute(cell); }

 private:
  visibility::CellLodRule rule_;
  std::unique_ptr<VisibilityEngine> inner_;
};

constexpr std::array<std::pair<DovCubes, const char*>, 2> kDovCubes = {{{DovCubes::kRays, "rays"}, {DovCubes::kExact, "exact"}}};

std::string listed(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

std::vector<std::string> dov_cubes_names() {
  std::vector<std::string> names;
  for (const auto& [cubes, name] : kDovCubes) names.push_back(name);
  return names;
}

std::string dov_cubes_name(DovCubes cubes) {
  for (const auto& [c, name] : kDovCubes)
    if (c == cubes) return name;
  return "?";
}

DovCubes parse_dov_cubes(const std::string& name) {
  for (const auto& [cubes, n] : kDovCubes)
    if (n == name) return cubes;
  fail("--dov-cubes '" + name + "'", "unknown cube-map mode; the modes are " + listed(dov_cubes_names()));
}

std::vector<std::string> engine_names() { return {"sampling", "dov", "conservative", "vlod"}; }

std::unique_ptr<VisibilityEngine> make_engine(const std::string& name, const World& world,
                                              const EngineOptions& options) {
  if (name == "sampling") return std::make_unique<visibility::SamplingEngine>(world, options);
  if (name == "dov") return std::make_unique<DovWithPrior>(world, options);
  if (name == "conservative") {
    ConservativeParams params;
    params.refine_levels = options.refine_levels;
    params.smallest_hole = options.smallest_hole;
    params.smallest_occluder = options.smallest_occluder;
    return make_conservative_engine(world, params);
  }
  if (name == "vlod") return std::make_unique<VlodEngine>(world, options);
  fail("visibility engine '" + name + "'", "unknown; the engines are " + listed(engine_names()));
}

}  // namespace cellwalk
