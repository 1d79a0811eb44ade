// The process's resident memory, from /proc/self/status: what a build or walk really used.
#pragma once

#include <cstdint>

namespace cellwalk {

uint64_t peak_rss_bytes();     // VmHWM
uint64_t current_rss_bytes();  // VmRSS

}  // namespace cellwalk
