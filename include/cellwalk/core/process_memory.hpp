// The process's resident memory, from /proc/self/status: what a build or walk really used.
#pragma once

#include <cstdint>

namespace cellwalk {

uint64_t peak_rss_bytes();     // VmHWM
uint64_t current_rss_bytes();  // VmRSS
// Resets VmHWM to the current RSS (Linux ≥ 4.0, /proc/self/clear_refs), so peak_rss_bytes()
// measures from here. Returns false where the kernel does not allow it.
bool reset_peak_rss();

// Gives the kernel back every whole free page the heap holds, wherever it lies. Why: glibc
// raises its mmap threshold to the largest block freed so far (up to 32 MiB), so once a decoded
// mesh has been freed, later meshes come from the heap, and the holes evicted meshes leave stay
// resident — bytes a budget that counts live blocks cannot see (on a 6 × 6 bunny lattice at
// 20 MiB, 2–9 MiB of the process's peak). Fixing the threshold instead costs llvmpipe, whose
// per-frame blocks it would map and unmap, 2–2.5× the frame time. Call it between frames: it
// costs a walk over the free chunks. Thread-safe (it takes each arena's lock). No-op off glibc.
void return_freed_heap();

}  // namespace cellwalk
