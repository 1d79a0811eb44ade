// MemoryBudget: a lock-free hard byte budget (DESIGN.md "Out-of-core for real").
#include "cellwalk/store/memory_budget.hpp"

#include "cellwalk/core/error.hpp"

namespace cellwalk {

bool MemoryBudget::try_reserve(uint64_t bytes) {
  uint64_t current = used_.load(std::memory_order_relaxed);
  uint64_t next = 0;
  do {
    next = current + bytes;
    if (next < current || (limit_ != 0 && next > limit_)) return false;
  } while (!used_.compare_exchange_weak(current, next, std::memory_order_acq_rel,
                                        std::memory_order_relaxed));
  // `next` is a value used() really had, so raising peak to it keeps peak exact.
  uint64_t peak = peak_.load(std::memory_order_relaxed);
  while (peak < next &&
         !peak_.compare_exchange_weak(peak, next, std::memory_order_acq_rel,
                                      std::memory_order_relaxed)) {
  }
  return true;
}

void MemoryBudget::release(uint64_t bytes) {
  const uint64_t before = used_.fetch_sub(bytes, std::memory_order_acq_rel);
  if (before < bytes) fail("MemoryBudget::release", "released more bytes than were reserved");
}

}  // namespace cellwalk
