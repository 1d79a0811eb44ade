// The visibility engines cellwalk has, by name (issue 4): "sampling" (Embree rays, vLOD §5 as
// sampling), "dov" (HDoV thesis §5.5.2 cube maps, with sampling as its step 1 so objects that
// cover no pixel still get DoV_s) and "conservative" (vLOD §5.2 / HDoV §5.5.1, its own file).
#include <memory>

#include "cellwalk/precompute/conservative_visibility.hpp"
#include "cellwalk/core/error.hpp"
#include "precompute/dov_engine.hpp"
#include "precompute/sampling_engine.hpp"

namespace cellwalk {

namespace {

// DoV with its step-1 engine owned beside it.
class DovWithPrior : public VisibilityEngine {
 public:
  DovWithPrior(const World& world, const EngineOptions& options)
      : prior_(world, options), dov_(world, options, &prior_) {}
  std::string name() const override { return dov_.name(); }
  bool conservative() const override { return false; }
  VisibleSet compute(const ViewCell& cell) const override { return dov_.compute(cell); }

 private:
  visibility::SamplingEngine prior_;
  visibility::DovEngine dov_;
};

}  // namespace

std::vector<std::string> engine_names() { return {"sampling", "dov", "conservative"}; }

std::unique_ptr<VisibilityEngine> make_engine(const std::string& name, const World& world,
                                              const EngineOptions& options) {
  if (name == "sampling") return std::make_unique<visibility::SamplingEngine>(world, options);
  if (name == "dov") return std::make_unique<DovWithPrior>(world, options);
  if (name == "conservative") {
    ConservativeParams params;
    params.refine_levels = options.refine_levels;
    return make_conservative_engine(world, params);
  }
  std::string known;
  for (const std::string& n : engine_names()) known += (known.empty() ? "" : ", ") + n;
  fail("visibility engine '" + name + "'", "unknown; the engines are " + known);
}

}  // namespace cellwalk
