// The process's memory as the kernel sees it: the heap's resident bytes stay near its live bytes
// when return_freed_heap() runs between frames (cellwalk/core/process_memory.hpp).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <vector>

#include "cellwalk/core/process_memory.hpp"
#include "cellwalk/core/random.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

constexpr uint64_t kMiB = 1048576;
constexpr uint64_t kLiveBound = 8 * kMiB;

// A geometry cache in miniature: blocks of 150 KiB to 3 MiB (decoded meshes of every size), each
// written whole, the oldest freed while the live bytes exceed kLiveBound; a frame loads one
// block. It starts by freeing a 6 MiB block, as a walk frees its first evicted mesh. Returns the
// largest resident excess over the live bytes seen, relative to the resident bytes before the
// first block; with `give_back`, return_freed_heap() runs after every frame.
uint64_t largest_excess_of_a_mesh_cache(bool give_back) {
  const uint64_t start = current_rss_bytes();
  void* first = std::malloc(6 * kMiB);
  std::memset(first, 1, 6 * kMiB);
  std::free(first);
  Random random(7);
  std::deque<std::pair<void*, uint64_t>> live;
  uint64_t live_bytes = 0, excess = 0;
  for (int i = 0; i < 400; ++i) {
    const uint64_t bytes = 150 * 1024 + random.next() % (3 * kMiB - 150 * 1024);
    void* block = std::malloc(bytes);
    std::memset(block, int(i & 0xff), bytes);
    live.emplace_back(block, bytes);
    live_bytes += bytes;
    while (live_bytes > kLiveBound) {
      std::free(live.front().first);
      live_bytes -= live.front().second;
      live.pop_front();
    }
    if (give_back) return_freed_heap();
    const uint64_t now = current_rss_bytes();
    if (now > start + live_bytes) excess = std::max(excess, now - start - live_bytes);
  }
  for (const auto& [block, bytes] : live) std::free(block);
  return excess;
}

// Runs the cache in a child, apart from the test binary's other allocations, and returns its
// excess in bytes (UINT64_MAX, and a failure, where it could not run).
uint64_t excess_in_a_child(bool give_back) {
  int fds[2];
  if (pipe(fds) != 0) {
    ADD_FAILURE() << "pipe: " << std::strerror(errno);
    return UINT64_MAX;
  }
  const pid_t child = fork();
  if (child < 0) ADD_FAILURE() << "fork: " << std::strerror(errno);
  if (child == 0) {
    close(fds[0]);
    alarm(60);  // a child that hangs ends, and the parent reads no answer
    const uint64_t excess = largest_excess_of_a_mesh_cache(give_back);
    const bool written = write(fds[1], &excess, sizeof excess) == ssize_t(sizeof excess);
    _exit(written ? 0 : 1);
  }
  close(fds[1]);
  uint64_t excess = UINT64_MAX;
  const bool read_whole = child > 0 && read(fds[0], &excess, sizeof excess) == ssize_t(sizeof excess);
  close(fds[0]);
  int status = 0;
  if (child > 0) waitpid(child, &status, 0);
  EXPECT_TRUE(read_whole && WIFEXITED(status) && WEXITSTATUS(status) == 0);
  return excess;
}

// The budget counts live blocks; the kernel counts resident pages. With the freed pages given
// back after every frame, the two agree within rounding; without, glibc's dynamic threshold,
// raised by the first freed block, lets evicted blocks' holes stay resident — the miss the
// process budget had.
TEST(ProcessMemory, HeapGivenBackStaysWithinItsLiveBytes) {
  if (test::kUnderAddressSanitizer) GTEST_SKIP() << "ASan's allocator replaces glibc's";
#if !defined(__GLIBC__)
  GTEST_SKIP() << "return_freed_heap() gives pages back only on glibc";
#endif
  const uint64_t given_back = excess_in_a_child(true), kept = excess_in_a_child(false);
  std::printf("resident beyond live: %.2f MiB given back, %.2f MiB kept by the heap\n",
              double(given_back) / kMiB, double(kept) / kMiB);
  EXPECT_LE(given_back, kMiB);
  EXPECT_GT(kept, given_back) << "the mesh cache no longer shows what giving back is for";
}

}  // namespace
}  // namespace cellwalk
