// MemoryBudget: the hard byte budget of one run, shared by every cache (decoded geometry, index
// pages, visibility data). DESIGN.md "Out-of-core for real": the budget is never exceeded.
// HDoV thesis digest §2.1 (one Buffer Manager over the data-structure and scene-graph buffers).
//
// Thread-safety: every member may be called concurrently. A reservation that would take used()
// above limit() fails and changes nothing; the caller evicts and retries.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace cellwalk {

class MemoryBudget {
 public:
  // limit_bytes == 0 means unlimited (used() and peak() are still tracked).
  explicit MemoryBudget(uint64_t limit_bytes = 0) : limit_(limit_bytes) {}
  MemoryBudget(const MemoryBudget&) = delete;
  MemoryBudget& operator=(const MemoryBudget&) = delete;

  // Adds `bytes` to used() if the result stays within limit(); returns whether it did.
  bool try_reserve(uint64_t bytes);
  // REQUIRES: `bytes` were reserved earlier and not yet released.
  void release(uint64_t bytes);

  uint64_t used() const { return used_.load(std::memory_order_acquire); }
  // The largest value used() has ever had (exact: every successful reservation raises it).
  uint64_t peak() const { return peak_.load(std::memory_order_acquire); }
  uint64_t limit() const { return limit_; }
  // Whether an item of `bytes` could ever fit, i.e. with nothing else reserved.
  bool could_fit(uint64_t bytes) const { return limit_ == 0 || bytes <= limit_; }

 private:
  const uint64_t limit_;
  std::atomic<uint64_t> used_{0};
  std::atomic<uint64_t> peak_{0};
};

}  // namespace cellwalk
