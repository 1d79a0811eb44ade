// Prefetcher: a priority queue of loads with cancellation, run by worker threads or stepped
// deterministically between frames (HDoV thesis digest §3.5, §2.1; seeds/003 prioritized
// prefetching).
#include "cellwalk/store/prefetcher.hpp"

#include <algorithm>
#include <chrono>

#include "cellwalk/core/error.hpp"

namespace cellwalk {

Prefetcher::Prefetcher(BufferManager& cache, PrefetcherOptions options)
    : cache_(cache), options_(options) {
  if (options_.max_in_flight == 0) fail("Prefetcher", "max_in_flight must be at least 1");
  for (unsigned i = 0; i < options_.threads; ++i) workers_.emplace_back([this] { worker(); });
}

Prefetcher::~Prefetcher() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    stats_.cancelled += queue_.size();
    queue_.clear();
    order_.clear();
    by_epoch_.clear();
  }
  changed_.notify_all();
  for (std::thread& thread : workers_) thread.join();
}

void Prefetcher::submit(PrefetchRequest request) {
  {
    std::lock_guard lock(mutex_);
    ++stats_.submitted;
    if (queue_.contains(request.key)) {
      erase_locked(request.key);
      ++stats_.replaced;
    }
    const Order order{-request.priority, next_sequence_};
    by_epoch_.emplace(request.epoch, order);
    order_.emplace(order, request.key);
    const CacheKey key = request.key;
    queue_.emplace(key, Queued{std::move(request), next_sequence_++});
  }
  changed_.notify_one();
}

// REQUIRES: mutex_ held and `key` queued.
void Prefetcher::erase_locked(CacheKey key) {
  auto it = queue_.find(key);
  const Order order{-it->second.request.priority, it->second.sequence};
  by_epoch_.erase({it->second.request.epoch, order});
  order_.erase(order);
  queue_.erase(it);
}

bool Prefetcher::cancel(CacheKey key) {
  std::lock_guard lock(mutex_);
  if (!queue_.contains(key)) return false;
  erase_locked(key);
  ++stats_.cancelled;
  changed_.notify_all();  // wait_idle() may be waiting for an empty queue
  return true;
}

size_t Prefetcher::cancel_older_than(uint64_t epoch) {
  std::lock_guard lock(mutex_);
  size_t dropped = 0;
  while (!by_epoch_.empty() && by_epoch_.begin()->first < epoch) {
    erase_locked(order_.at(by_epoch_.begin()->second));
    ++dropped;
  }
  stats_.cancelled += dropped;
  changed_.notify_all();
  return dropped;
}

// REQUIRES: mutex_ held. Takes the highest-priority request off the queue.
std::optional<PrefetchRequest> Prefetcher::pop_locked() {
  if (order_.empty()) return std::nullopt;
  const CacheKey key = order_.begin()->second;
  PrefetchRequest request = std::move(queue_.at(key).request);
  erase_locked(key);
  ++stats_.started;
  return request;
}

// Runs one request without holding mutex_; the cache does its own locking.
void Prefetcher::execute(const PrefetchRequest& request) {
  enum class Outcome { kLoaded, kSkipped, kNotAdmitted, kFailed } outcome = Outcome::kFailed;
  std::string error;
  try {
    if (cache_.resident_or_loading(request.key)) {
      outcome = Outcome::kSkipped;
    } else {
      outcome = cache_.prefetch(request.key, request.meta, request.loader) ? Outcome::kLoaded
                                                                          : Outcome::kNotAdmitted;
    }
  } catch (const std::exception& e) {
    error = e.what();
  }
  std::lock_guard lock(mutex_);
  switch (outcome) {
    case Outcome::kLoaded: ++stats_.loaded; break;
    case Outcome::kSkipped: ++stats_.skipped; break;
    case Outcome::kNotAdmitted: ++stats_.not_admitted; break;
    case Outcome::kFailed:
      ++stats_.failed;
      stats_.last_error = error;
      break;
  }
}

void Prefetcher::worker() {
  std::unique_lock lock(mutex_);
  while (true) {
    changed_.wait(lock, [&] {
      return stopping_ || (!order_.empty() && in_flight_ < options_.max_in_flight);
    });
    if (stopping_) return;
    std::optional<PrefetchRequest> request = pop_locked();
    ++in_flight_;
    stats_.max_in_flight_seen = std::max<uint64_t>(stats_.max_in_flight_seen, in_flight_);
    lock.unlock();
    execute(*request);
    lock.lock();
    --in_flight_;
    changed_.notify_all();
  }
}

size_t Prefetcher::step(size_t max_requests) { return step_while(max_requests, [] { return true; }); }

size_t Prefetcher::step_for(double ms) {
  const auto start = std::chrono::steady_clock::now();
  return step_while(SIZE_MAX, [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() < ms;
  });
}

size_t Prefetcher::step_while(size_t max_requests, const std::function<bool()>& more) {
  if (options_.threads != 0) fail("Prefetcher::step", "only for deterministic mode (threads = 0)");
  size_t ran = 0;
  for (; ran < max_requests && more(); ++ran) {
    std::optional<PrefetchRequest> request;
    {
      std::lock_guard lock(mutex_);
      request = pop_locked();
      if (!request) break;
      in_flight_ = 1;
      stats_.max_in_flight_seen = std::max<uint64_t>(stats_.max_in_flight_seen, 1);
    }
    execute(*request);
    std::lock_guard lock(mutex_);
    in_flight_ = 0;
  }
  return ran;
}

size_t Prefetcher::run_until_idle() { return step(SIZE_MAX); }

void Prefetcher::wait_idle() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return order_.empty() && in_flight_ == 0; });
}

size_t Prefetcher::queued() const {
  std::lock_guard lock(mutex_);
  return queue_.size();
}

PrefetchStats Prefetcher::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

}  // namespace cellwalk
