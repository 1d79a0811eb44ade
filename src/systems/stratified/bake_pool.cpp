// Stratified thesis §3.1.2 (digest 002 §3.6): far-field baking on several threads of one process.
#include "cellwalk/systems/stratified/bake_pool.hpp"

#include <condition_variable>
#include <exception>
#include <map>
#include <mutex>
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
  std::exception_ptr error;
  bool stop = false;
  uint64_t triangles = 0;
  std::vector<std::thread> workers;  // last: started once everything they use exists

  Impl(const World& w, const BakeSettings& s, int threads, std::vector<BakeJob> j)
      : world(w), settings(s), jobs(std::move(j)), window(2 * size_t(threads)) {
    if (threads < 1) fail("stratify", "bake threads " + std::to_string(threads) + " must be at least 1");
    for (int t = 0; t < threads; ++t) workers.emplace_back([this] { work(); });
  }

  ~Impl() {
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
        }
        const uint64_t before = baker.triangles_drawn();
        StratifiedSizes unused;
        std::vector<uint8_t> record = encode_far_field(baker.bake(jobs[i].centre, jobs[i].b, jobs[i].near), jobs[i].b, unused);
        {
          std::lock_guard lock(mutex);
          triangles += baker.triangles_drawn() - before;
          ready.emplace(i, std::move(record));
        }
        changed.notify_all();
      }
    } catch (...) {
      {
        std::lock_guard lock(mutex);
        if (!error) error = std::current_exception();
      }
      changed.notify_all();
    }
  }

  std::vector<uint8_t> next() {
    std::unique_lock lock(mutex);
    if (taken >= jobs.size()) fail("stratify", "the bake pool has no job left to give");
    changed.wait(lock, [&] { return ready.count(taken) || error; });
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
