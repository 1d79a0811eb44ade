#include "core/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace cellwalk {

Progress::Progress(std::string label, uint64_t total)
    : label_(std::move(label)),
      total_(total),
      enabled_(isatty(STDERR_FILENO) != 0),
      last_(std::chrono::steady_clock::now()) {}

Progress::~Progress() {
  finish();
}

void Progress::update(uint64_t done) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  draw(done);
}

void Progress::draw(uint64_t done) {
  constexpr int kWidth = 30;
  if (total_ == 0) {
    std::fprintf(stderr, "\r%s %llu", label_.c_str(), static_cast<unsigned long long>(done));
  } else {
    const double f = done >= total_ ? 1.0 : static_cast<double>(done) / static_cast<double>(total_);
    const int filled = static_cast<int>(f * kWidth);
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%  %llu", label_.c_str(), filled,
                 "==============================", kWidth - filled, "", static_cast<int>(f * 100),
                 static_cast<unsigned long long>(done));
  }
  std::fflush(stderr);
  drawn_ = true;
}

void Progress::finish() {
  if (!drawn_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
  drawn_ = false;
}

}  // namespace cellwalk
