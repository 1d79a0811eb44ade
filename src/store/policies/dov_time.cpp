// DoV and DoV-Time (DT) node-cache policies: HDoV thesis §5.7, digest §3.11.
//   DoV: evict the smallest DoV.
//   DT:  evict the smallest f(DoV, T) = DoV + κ·T, κ = 0.001, T = the entry's latest access time.
// One mechanism: DoV is DT with κ = 0. Digest [GAP]s settled here: the DoV is the one passed with
// the latest access (the entry's DoV in the cell current then), keys are refreshed on every hit,
// and T counts accesses to this cache (1, 2, ...), so κ·T grows by 1 every 1000 requests, the
// full range of a DoV. Ties go to the least recently used entry.
#include "cellwalk/replacement_policy.hpp"

namespace cellwalk {
namespace {

class DovTimePolicy final : public ScoredPolicy {
 public:
  explicit DovTimePolicy(double kappa) : kappa_(kappa) {}

 private:
  Score score(const Entry& entry) const override {
    const double t = static_cast<double>(entry.last_access);
    return {static_cast<double>(entry.meta.dov) + kappa_ * t, t, 0.0};
  }

  const double kappa_;
};

}  // namespace

std::unique_ptr<ReplacementPolicy> make_dov_policy() { return std::make_unique<DovTimePolicy>(0.0); }

std::unique_ptr<ReplacementPolicy> make_dov_time_policy(double kappa) {
  return std::make_unique<DovTimePolicy>(kappa);
}

}  // namespace cellwalk
