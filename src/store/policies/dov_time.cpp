// DoV and DoV-Time (DT) node-cache policies: HDoV thesis §5.7, digest §3.11.
//   DoV: evict the smallest DoV.
//   DT:  evict the smallest f(DoV, T) = DoV + κ·T, κ = 0.001, T = the entry's latest access time.
// One mechanism: DoV is DT with κ = 0. Digest [GAP]s settled here: the DoV is the one passed with
// the latest access (the entry's DoV in the cell current then), keys are refreshed on every hit.
// The time unit is the caller's choice (DovTimeClock): accesses to this cache (1, 2, ...; κ·T
// grows by 1 every 1000 requests), or queries, counted by on_query() (κ·T grows by 1 every 1000
// searches, the thesis's reading for the HDoV node cache). Ties go to the least recently used.
#include "cellwalk/store/replacement_policy.hpp"

namespace cellwalk {
namespace {

class DovTimePolicy final : public ScoredPolicy {
 public:
  DovTimePolicy(double kappa, DovTimeClock clock) : kappa_(kappa), clock_(clock) {}

  void on_query(const QueryContext&) override {
    // Scores depend only on each entry's own last time, so nothing is re-scored here.
    if (clock_ == DovTimeClock::kQueries) advance_query_clock();
  }

 private:
  Score score(const Entry& entry) const override {
    const double access = static_cast<double>(entry.last_access);
    const double t = clock_ == DovTimeClock::kQueries ? static_cast<double>(entry.last_query) : access;
    return {static_cast<double>(entry.meta.dov) + kappa_ * t, access, 0.0};
  }

  const double kappa_;
  const DovTimeClock clock_;
};

}  // namespace

std::unique_ptr<ReplacementPolicy> make_dov_policy() {
  return std::make_unique<DovTimePolicy>(0.0, DovTimeClock::kAccesses);
}

std::unique_ptr<ReplacementPolicy> make_dov_time_policy(double kappa, DovTimeClock clock) {
  return std::make_unique<DovTimePolicy>(kappa, clock);
}

}  // namespace cellwalk
