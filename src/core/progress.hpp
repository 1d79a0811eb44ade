// A one-line progress indicator for long runs: "\r<label> [=====     ]  45%  12345" on stderr,
// redrawn at most 10 times a second and only when stderr is a terminal (logs and pipes stay
// clean). Not thread-safe: one producer calls update().
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace cellwalk {

class Progress {
 public:
  // `total` 0 means unknown: the line then shows the count alone.
  Progress(std::string label, uint64_t total);
  ~Progress();  // clears the line if finish() was not called
  void update(uint64_t done);
  // Clears the line so the caller's summary starts at column 0.
  void finish();

 private:
  void draw(uint64_t done);

  std::string label_;
  uint64_t total_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace cellwalk
