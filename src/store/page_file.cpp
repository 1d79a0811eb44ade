// PageFile: whole-page reads with pread(2), EINTR and short-read handling, O_DIRECT or
// drop-behind to keep the OS page cache out of measurements, and exact counters.
// DESIGN.md "Out-of-core for real"; HDoV thesis digest §2.1 (Retrieval Engine), §8.2
// ("bypass the page cache with O_DIRECT or posix_fadvise(DONTNEED)").
#include "cellwalk/store/page_file.hpp"

#include <chrono>
#include <thread>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <algorithm>
#include <cstdint>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/http_read_source.hpp"

namespace cellwalk {
namespace {

// Consecutive reads without progress (EINTR, or a short read below the alignment unit) after
// which a read is reported as failed rather than retried forever.
constexpr int kMaxStalledReads = 64;

std::string at(const std::string& name, uint64_t offset) {
  return name + " @ byte " + std::to_string(offset);
}

std::string errno_text(int error_number) {
  return std::string(std::strerror(error_number)) + " (errno " + std::to_string(error_number) + ")";
}

int open_file(const std::string& path, int extra_flags) {
  return ::open(path.c_str(), O_RDONLY | O_CLOEXEC | extra_flags);
}

}  // namespace

const char* to_string(CacheBypass mode) {
  switch (mode) {
    case CacheBypass::kNone: return "os-cache";
    case CacheBypass::kDirect: return "o_direct";
    case CacheBypass::kDropBehind: return "fadvise-dontneed";
  }
  return "?";
}

void AlignedFree::operator()(void* p) const { std::free(p); }

AlignedBuffer make_aligned_buffer(size_t bytes, size_t alignment) {
  void* p = nullptr;
  if (int rc = posix_memalign(&p, alignment, bytes == 0 ? alignment : bytes); rc != 0) {
    fail("make_aligned_buffer", "cannot allocate " + std::to_string(bytes) + " bytes: " + errno_text(rc));
  }
  return AlignedBuffer(static_cast<std::byte*>(p));
}

// ---- FileReadSource ----

FileReadSource::FileReadSource(const std::string& path, bool bypass, size_t page_size)
    : path_(path) {
  if (bypass) {
    fd_ = open_file(path, O_DIRECT);
    if (fd_ >= 0) mode_ = CacheBypass::kDirect;
  }
  if (fd_ < 0) open_buffered();
  struct stat st {};
  if (::fstat(fd_, &st) != 0) {
    const int e = errno;
    ::close(fd_);
    fail(path_, "cannot stat: " + errno_text(e));
  }
  size_ = static_cast<uint64_t>(st.st_size);
  if (mode_ == CacheBypass::kDirect && !direct_read_works(page_size)) {
    ::close(fd_);
    open_buffered();
  }
  if (bypass && mode_ == CacheBypass::kNone) mode_ = CacheBypass::kDropBehind;
}

FileReadSource::~FileReadSource() {
  if (fd_ >= 0) ::close(fd_);
}

void FileReadSource::open_buffered() {
  fd_ = open_file(path_, 0);
  if (fd_ < 0) fail(path_, "cannot open for reading: " + errno_text(errno));
  mode_ = CacheBypass::kNone;
}

// Some file systems accept O_DIRECT at open and refuse the reads (EINVAL); others need blocks
// larger than a small page. One aligned read of the first page tells.
bool FileReadSource::direct_read_works(size_t page_size) {
  if (size_ < page_size) return true;  // no whole page to read, nothing can go wrong
  AlignedBuffer probe = make_aligned_buffer(page_size, direct_alignment_);
  long got = -1;
  do {
    got = ::pread(fd_, probe.get(), page_size, 0);
  } while (got < 0 && errno == EINTR);
  return got >= 0;
}

long FileReadSource::read_at(void* dst, size_t bytes, uint64_t offset) {
  const ssize_t got = ::pread(fd_, dst, bytes, static_cast<off_t>(offset));
  return got < 0 ? -errno : static_cast<long>(got);
}

void FileReadSource::after_read(uint64_t offset, size_t bytes) {
  if (mode_ != CacheBypass::kDropBehind) return;
  // Advisory: a failure only means the page cache keeps the pages.
  (void)::posix_fadvise(fd_, static_cast<off_t>(offset), static_cast<off_t>(bytes),
                        POSIX_FADV_DONTNEED);
}

// ---- FaultInjectingSource ----

void FaultInjectingSource::add_rule(const Rule& rule) {
  std::lock_guard lock(mutex_);
  rules_.push_back(rule);
}

long FaultInjectingSource::read_at(void* dst, size_t bytes, uint64_t offset) {
  std::optional<Rule> hit;
  {
    std::lock_guard lock(mutex_);
    for (Rule& rule : rules_) {
      const bool overlaps = offset < rule.end && rule.begin < offset + bytes;
      if (!overlaps || rule.remaining == 0) continue;
      if (rule.remaining > 0) --rule.remaining;
      hit = rule;
      break;
    }
  }
  if (!hit) return inner_->read_at(dst, bytes, offset);
  switch (hit->fault) {
    case Fault::kError: return -hit->error_number;
    case Fault::kInterrupt: return -EINTR;
    case Fault::kShort: {
      // Read the whole request (an O_DIRECT source refuses unaligned sizes), report less.
      const long got = inner_->read_at(dst, bytes, offset);
      return got < 0 ? got : std::min(got, static_cast<long>(hit->short_bytes));
    }
  }
  return -EIO;
}

// ---- PageFile ----

namespace {

size_t checked_page_size(size_t page_size) {
  if (page_size < 512 || (page_size & (page_size - 1)) != 0) {
    fail("PageFile", "page size " + std::to_string(page_size) + " is not a power of two >= 512");
  }
  return page_size;
}

}  // namespace

PageFile::PageFile(const std::string& path, Options options)
    : page_size_(checked_page_size(options.page_size)) {
  if (is_http_url(path)) {
    source_ = std::make_unique<HttpReadSource>(path);
  } else {
    auto file = std::make_unique<FileReadSource>(path, options.bypass_cache, page_size_);
    mode_ = file->mode();
    source_ = std::move(file);
  }
  if (options.read_latency_us > 0 || options.read_bandwidth_mbit > 0)
    source_ = std::make_unique<DelayedReadSource>(std::move(source_), options.read_latency_us, options.read_bandwidth_mbit);
}

long DelayedReadSource::read_at(void* dst, size_t bytes, uint64_t offset) {
  std::this_thread::sleep_for(std::chrono::microseconds(latency_us_));
  const long got = inner_->read_at(dst, bytes, offset);
  if (got > 0 && bandwidth_mbit_ > 0)
    std::this_thread::sleep_for(std::chrono::duration<double>(double(got) * 8.0 / (bandwidth_mbit_ * 1e6)));
  return got;
}

PageFile::PageFile(std::unique_ptr<ReadSource> source, size_t page_size)
    : source_(std::move(source)), page_size_(checked_page_size(page_size)) {}

void PageFile::read(uint64_t first_page, uint64_t page_count, void* dst) {
  const uint64_t offset = first_page * page_size_;
  const uint64_t bytes = page_count * page_size_;
  if (first_page > UINT64_MAX / page_size_ || page_count > UINT64_MAX / page_size_ ||
      offset > source_->size() || bytes > source_->size() - offset) {
    fail(at(name(), offset), "pages [" + std::to_string(first_page) + ", " +
                                 std::to_string(first_page + page_count) +
                                 ") reach past the end of the file (" +
                                 std::to_string(source_->size()) + " bytes)");
  }
  const size_t alignment = source_->alignment();
  if (alignment > 1 && reinterpret_cast<uintptr_t>(dst) % alignment != 0) {
    AlignedBuffer bounce = make_aligned_buffer(bytes, alignment);
    read_exact(offset, bytes, bounce.get());
    std::memcpy(dst, bounce.get(), bytes);
  } else {
    read_exact(offset, bytes, static_cast<std::byte*>(dst));
  }
  requests_.fetch_add(1, std::memory_order_relaxed);
  pages_.fetch_add(page_count, std::memory_order_relaxed);
  bytes_.fetch_add(bytes, std::memory_order_relaxed);
}

// REQUIRES: [offset, offset + bytes) lies inside the file; dst meets the source's alignment.
void PageFile::read_exact(uint64_t offset, size_t bytes, std::byte* dst) {
  // An aligned source only continues from whole pages: a partial page is read again.
  const size_t unit = source_->alignment() > 1 ? page_size_ : 1;
  size_t done = 0;
  int stalled = 0;
  while (done < bytes) {
    const long got = source_->read_at(dst + done, bytes - done, offset + done);
    syscalls_.fetch_add(1, std::memory_order_relaxed);
    if (got < 0 && got != -EINTR) {
      fail(at(name(), offset + done),
           "read of " + std::to_string(bytes - done) + " bytes failed: " + errno_text(static_cast<int>(-got)));
    }
    if (got == 0) fail(at(name(), offset + done), "unexpected end of file (did the file shrink?)");
    const size_t progress = got < 0 ? 0 : static_cast<size_t>(got) / unit * unit;
    if (progress == 0) {
      if (++stalled > kMaxStalledReads) {
        fail(at(name(), offset + done), "no progress after " + std::to_string(kMaxStalledReads) +
                                            " interrupted or short reads");
      }
      continue;
    }
    stalled = 0;
    done += progress;
  }
  source_->after_read(offset, bytes);
}

PageFileCounters PageFile::counters() const {
  return {requests_.load(std::memory_order_relaxed), pages_.load(std::memory_order_relaxed),
          bytes_.load(std::memory_order_relaxed), syscalls_.load(std::memory_order_relaxed)};
}

void PageFile::reset_counters() {
  requests_.store(0, std::memory_order_relaxed);
  pages_.store(0, std::memory_order_relaxed);
  bytes_.store(0, std::memory_order_relaxed);
  syscalls_.store(0, std::memory_order_relaxed);
}

}  // namespace cellwalk
