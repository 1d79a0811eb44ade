// Prefetcher: loads items the caller expects to need soon into a BufferManager, highest priority
// first (HDoV thesis digest §3.5 "Prefetching", §2.1 "Prefetching Engine"; seeds/003
// "Prioritized object prefetching").
//
// Two modes. Background (threads > 0): worker threads take requests while fewer than
// max_in_flight run. Deterministic (threads == 0): nothing runs until the caller calls step() or
// run_until_idle() on its own thread, e.g. between frames, so an experiment replays exactly; the
// digest (§2.1) notes the thesis itself fetches between frames on one thread.
//
// Requests become useless when the viewer moves on: cancel(key) drops a queued request,
// cancel_older_than(epoch) drops every queued request of an older epoch (use the frame number).
// A request already running is not interrupted; its item is admitted (the I/O is paid).
//
// Thread-safety: all members may be called concurrently, except step() and run_until_idle(),
// which are for deterministic mode. The destructor drops queued requests and waits for running
// ones. REQUIRES: the BufferManager outlives the Prefetcher.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "cellwalk/store/buffer_manager.hpp"

namespace cellwalk {

struct PrefetchRequest {
  CacheKey key = 0;
  double priority = 0.0;  // larger runs first; ties in submission order
  uint64_t epoch = 0;     // e.g. the frame that asked; see cancel_older_than
  EntryMeta meta;         // handed to the cache's policy on admission
  ItemLoader loader;
};

struct PrefetcherOptions {
  unsigned threads = 1;      // 0 = deterministic mode
  size_t max_in_flight = 4;  // requests running at once (background mode); REQUIRES >= 1
};

struct PrefetchStats {
  uint64_t submitted = 0;
  uint64_t replaced = 0;      // a queued request for the same key was replaced by a newer one
  uint64_t cancelled = 0;     // dropped from the queue before running
  uint64_t started = 0;       // taken from the queue
  uint64_t loaded = 0;        // loaded and admitted to the cache
  uint64_t skipped = 0;       // already resident or being loaded when started
  uint64_t not_admitted = 0;  // loaded but did not fit the budget
  uint64_t failed = 0;        // the loader threw
  uint64_t max_in_flight_seen = 0;
  std::string last_error;     // what() of the latest failure
};

class Prefetcher {
 public:
  Prefetcher(BufferManager& cache, PrefetcherOptions options);
  ~Prefetcher();
  Prefetcher(const Prefetcher&) = delete;
  Prefetcher& operator=(const Prefetcher&) = delete;

  // Queues `request`; a queued request with the same key is replaced.
  void submit(PrefetchRequest request);
  // Drops the queued request for `key`; returns whether there was one.
  bool cancel(CacheKey key);
  // Drops every queued request with epoch < `epoch`; returns how many.
  size_t cancel_older_than(uint64_t epoch);

  // Deterministic mode: runs up to `max_requests` queued requests on this thread, highest
  // priority first; returns how many ran. REQUIRES: threads == 0.
  size_t step(size_t max_requests);
  // Deterministic mode: runs queued requests, highest priority first, while less than `ms`
  // milliseconds have passed since the call began (Li & Chiang's t_p, the time a frame allows
  // for prefetching); a request once started runs to its end. Returns how many ran.
  // REQUIRES: threads == 0.
  size_t step_for(double ms);
  size_t run_until_idle();
  // Blocks until the queue is empty and nothing runs (background mode).
  void wait_idle();

  size_t queued() const;
  PrefetchStats stats() const;

 private:
  using Order = std::pair<double, uint64_t>;  // (-priority, sequence number)
  struct Queued {
    PrefetchRequest request;
    uint64_t sequence = 0;
  };

  // Runs queued requests while fewer than `max_requests` ran and `more()` says so (asked before each).
  size_t step_while(size_t max_requests, const std::function<bool()>& more);
  std::optional<PrefetchRequest> pop_locked();
  void erase_locked(CacheKey key);
  void execute(const PrefetchRequest& request);
  void worker();

  BufferManager& cache_;
  const PrefetcherOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::unordered_map<CacheKey, Queued> queue_;
  std::map<Order, CacheKey> order_;  // the priority queue
  std::set<std::pair<uint64_t, Order>> by_epoch_;
  uint64_t next_sequence_ = 0;
  size_t in_flight_ = 0;
  bool stopping_ = false;
  PrefetchStats stats_;
  std::vector<std::thread> workers_;
};

}  // namespace cellwalk
