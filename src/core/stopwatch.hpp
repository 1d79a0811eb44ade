// Wall-clock timing for frame statistics.
#pragma once

#include <chrono>

namespace cellwalk {

class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  // Milliseconds since construction or the last lap_ms().
  double ms() const { return std::chrono::duration<double, std::milli>(Clock::now() - start_).count(); }
  double lap_ms() {
    auto now = Clock::now();
    double elapsed = std::chrono::duration<double, std::milli>(now - start_).count();
    start_ = now;
    return elapsed;
  }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

}  // namespace cellwalk
