// Stratified thesis §3.1.2 (digest 002 §3.6): far-field baking on several threads of one process.
#include "cellwalk/systems/stratified/bake_pool.hpp"

#include <algorithm>
#include <condition_variable>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <system_error>
#include <thread>

#include "cellwalk/core/error.hpp"

namespace cellwalk::stratified {

struct BakePool::Impl {
  const World& world;
  const BakeSettings settings;
  const std::vector<BakeJob> jobs;
  const size_t window;  // results baked ahead of the one taken, at most
  std::mutex mutex;
  std::condition_variable changed;
  size_t next_job = 0, taken = 0;
  std::map<size_t, std::vector<uint8_t>> ready;
  std::set<size_t> baking;  // jobs a worker has taken and not finished
  std::exception_ptr error;
  bool stop = false;
  uint64_t triangles = 0;
  std::vector<std::thread> workers;  // last: started once everything they use exists

  Impl(const World& w, const BakeSettings& s, int threads, std::vector<BakeJob> j)
      : world(w), settings(s), jobs(std::move(j)), window(2 * size_t(std::max(threads, 1))) {
    if (threads < 1) fail("stratify", "bake threads " + std::to_string(threads) + " must be at least 1");
    threads = int(std::min<size_t>(size_t(threads), std::max<size_t>(jobs.size(), 1)));  // a context per job at most
    workers.reserve(size_t(threads));
    try {
      for (int t = 0; t < threads; ++t) workers.emplace_back([this] { work(); });
    } catch (const std::system_error& e) {
      stop_workers();
      fail("stratify", "cannot start bake thread " + std::to_string(workers.size() + 1) + " of " + std::to_string(threads) +
                           " (" + e.what() + "); bake with fewer --threads");
    }
  }

  ~Impl() { stop_workers(); }

  void stop_workers() {
    {
      std::lock_guard lock(mutex);
      stop = true;
    }
    changed.notify_all();
    for (std::thread& t : workers) t.join();
  }

  // A worker: its own baker (and GL context, made and destroyed on this thread), then jobs
  // until none is left, the pool stops or a job fails.
  void work() {
    try {
      FarFieldBaker baker(world, settings);
      while (true) {
        size_t i = 0;
        {
          std::unique_lock lock(mutex);
          changed.wait(lock, [&] { return stop || error || next_job >= jobs.size() || next_job < taken + window; });
          if (stop || error || next_job >= jobs.size()) return;
          i = next_job++;
          baking.insert(i);
        }
        const uint64_t before = baker.triangles_drawn();
        StratifiedSizes unused;
        std::vector<uint8_t> record;
        try {
          record = encode_far_field(baker.bake(jobs[i].centre, jobs[i].b, jobs[i].near), jobs[i].b, unused);
        } catch (...) {
          fail_job(i);
          return;
        }
        {
          std::lock_guard lock(mutex);
          triangles += baker.triangles_drawn() - before;
          baking.erase(i);
          ready.emplace(i, std::move(record));
        }
        changed.notify_all();
      }
    } catch (...) {  // the baker could not be made
      fail_job(std::nullopt);
    }
  }

  // Records the current exception as the pool's error; `job`, if any, is no longer baking.
  void fail_job(std::optional<size_t> job) {
    {
      std::lock_guard lock(mutex);
      if (job) baking.erase(*job);
      if (!error) error = std::current_exception();
    }
    changed.notify_all();
  }

  std::vector<uint8_t> next() {
    std::unique_lock lock(mutex);
    if (taken >= jobs.size()) fail("stratify", "the bake pool has no job left to give");
    // After a failure, the records baked before it still come out (a checkpoint keeps them).
    changed.wait(lock, [&] { return ready.count(taken) || (error && !baking.count(taken)); });
    const auto it = ready.find(taken);
    if (it == ready.end()) std::rethrow_exception(error);
    std::vector<uint8_t> record = std::move(it->second);
    ready.erase(it);
    ++taken;
    lock.unlock();
    changed.notify_all();  // the window moved on
    return record;
  }
};

BakePool::BakePool(const World& world, const BakeSettings& settings, int threads, std::vector<BakeJob> jobs)
    : impl_(std::make_unique<Impl>(world, settings, threads, std::move(jobs))) {}

BakePool::~BakePool() = default;

std::vector<uint8_t> BakePool::next() { return impl_->next(); }

uint64_t BakePool::triangles_drawn() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->triangles;
}

}  // namespace cellwalk::stratified
