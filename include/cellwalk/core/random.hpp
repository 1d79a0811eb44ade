// A deterministic random source. The standard library's distributions differ between
// implementations, so generators and paths use this instead: the same seed gives the same
// world and the same path on every machine and compiler.
#pragma once

#include <cstdint>

namespace cellwalk {

// SplitMix64 (Steele, Lea, Flood. Fast splittable pseudorandom number generators. 2014).
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}

  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  // Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [lo, hi]. REQUIRES: lo <= hi.
  int64_t integer(int64_t lo, int64_t hi) {
    return lo + static_cast<int64_t>(next() % static_cast<uint64_t>(hi - lo + 1));
  }
  bool chance(double p) { return uniform() < p; }
  // An independent stream, e.g. one per object, so that changing one object's draws does not
  // shift every later object.
  Random split(uint64_t salt) { return Random(next() ^ (salt * 0xD1B54A32D192ED03ull)); }

 private:
  uint64_t state_;
};

}  // namespace cellwalk
