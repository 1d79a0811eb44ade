// The process's resident memory, from /proc/self/status: what a build or walk really used.
#pragma once

#include <cstdint>

namespace cellwalk {

uint64_t peak_rss_bytes();     // VmHWM
uint64_t current_rss_bytes();  // VmRSS
// Resets VmHWM to the current RSS (Linux ≥ 4.0, /proc/self/clear_refs), so peak_rss_bytes()
// measures from here. Returns false where the kernel does not allow it.
bool reset_peak_rss();

}  // namespace cellwalk
