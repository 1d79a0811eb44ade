// PageFile: the store's read path, whole fixed-size pages of one world file (DESIGN.md "The world
// file", "Out-of-core for real"; HDoV thesis digest §2.1, the Retrieval Engine).
// Reads go through a ReadSource, the seam LevelDB calls Env: FileReadSource does pread(2) on a
// real file, FaultInjectingSource wraps another source and makes chosen reads fail or come back
// short, so tests can make the disk lie.
//
// Thread-safety: PageFile::read and the counters may be used from any number of threads at once.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace cellwalk {

// One positional read. Implementations must be safe to call concurrently.
class ReadSource {
 public:
  virtual ~ReadSource() = default;
  // Reads up to `bytes` at `offset` into `dst` with a single system call's semantics: returns the
  // number of bytes read (0 at end of file) or -errno (e.g. -EINTR, -EIO).
  virtual long read_at(void* dst, size_t bytes, uint64_t offset) = 0;
  virtual uint64_t size() const = 0;
  // Bytes `dst`, `bytes` and `offset` of read_at must be multiples of (1 = no requirement).
  virtual size_t alignment() const { return 1; }
  // Called after each successful read of [offset, offset + bytes): drop-behind hook.
  virtual void after_read(uint64_t /*offset*/, size_t /*bytes*/) {}
  // The name used in error messages.
  virtual const std::string& name() const = 0;
};

// How a FileReadSource keeps reads off the OS page cache.
enum class CacheBypass {
  kNone,        // ordinary buffered reads
  kDirect,      // O_DIRECT; buffers, offsets and sizes aligned to 4096 (or the page size)
  kDropBehind,  // buffered reads followed by posix_fadvise(POSIX_FADV_DONTNEED)
};
const char* to_string(CacheBypass mode);

// pread(2) on a file opened read-only. With `bypass` requested, tries O_DIRECT first and falls
// back to drop-behind when the file system refuses it (tmpfs: EINVAL at open or first read);
// mode() says which one is active.
class FileReadSource final : public ReadSource {
 public:
  // Throws Error naming the path if the file cannot be opened.
  FileReadSource(const std::string& path, bool bypass, size_t page_size);
  ~FileReadSource() override;
  FileReadSource(const FileReadSource&) = delete;
  FileReadSource& operator=(const FileReadSource&) = delete;

  long read_at(void* dst, size_t bytes, uint64_t offset) override;
  uint64_t size() const override { return size_; }
  size_t alignment() const override { return mode_ == CacheBypass::kDirect ? direct_alignment_ : 1; }
  void after_read(uint64_t offset, size_t bytes) override;
  const std::string& name() const override { return path_; }
  CacheBypass mode() const { return mode_; }

 private:
  bool direct_read_works(size_t page_size);
  void open_buffered();

  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0;
  CacheBypass mode_ = CacheBypass::kNone;
  size_t direct_alignment_ = 4096;
};

// A ReadSource for tests: forwards to `inner` except for reads that touch a faulty range.
// Thread-safety: rules may be added while reads run.
class FaultInjectingSource final : public ReadSource {
 public:
  enum class Fault {
    kError,     // the read returns -error_number
    kShort,     // the read returns at most `short_bytes` bytes (if > 0) - a partial read
    kInterrupt  // the read returns -EINTR `remaining` times, then behaves
  };
  struct Rule {
    uint64_t begin = 0, end = 0;  // byte range [begin, end) a read must overlap to be affected
    Fault fault = Fault::kError;
    int error_number = 5;  // EIO
    size_t short_bytes = 1;
    int remaining = -1;  // how many reads the rule affects; -1 = all
  };

  explicit FaultInjectingSource(std::unique_ptr<ReadSource> inner) : inner_(std::move(inner)) {}
  void add_rule(const Rule& rule);

  long read_at(void* dst, size_t bytes, uint64_t offset) override;
  uint64_t size() const override { return inner_->size(); }
  size_t alignment() const override { return inner_->alignment(); }
  void after_read(uint64_t offset, size_t bytes) override { inner_->after_read(offset, bytes); }
  const std::string& name() const override { return inner_->name(); }

 private:
  std::unique_ptr<ReadSource> inner_;
  std::mutex mutex_;
  std::vector<Rule> rules_;
};

// A slow disk or a slow link, for experiments (issue 18: Li & Chiang's cases on a slow disk;
// issue 20: a world behind a web server over an 80 ms link): forwards to `inner` after sleeping
// `latency_us` microseconds per read_at call, as a seek or a round trip would cost, and after
// the read sleeps as long as its bytes take at `bandwidth_mbit` (0: no limit).
// Thread-safety: as `inner`; concurrent reads wait side by side, as on a disk with a queue.
class DelayedReadSource final : public ReadSource {
 public:
  DelayedReadSource(std::unique_ptr<ReadSource> inner, uint32_t latency_us, double bandwidth_mbit = 0.0)
      : inner_(std::move(inner)), latency_us_(latency_us), bandwidth_mbit_(bandwidth_mbit) {}

  long read_at(void* dst, size_t bytes, uint64_t offset) override;
  uint64_t size() const override { return inner_->size(); }
  size_t alignment() const override { return inner_->alignment(); }
  void after_read(uint64_t offset, size_t bytes) override { inner_->after_read(offset, bytes); }
  const std::string& name() const override { return inner_->name(); }
  uint32_t latency_us() const { return latency_us_; }

 private:
  std::unique_ptr<ReadSource> inner_;
  uint32_t latency_us_;
  double bandwidth_mbit_;
};

struct PageFileCounters {
  uint64_t requests = 0;  // read() calls that succeeded
  uint64_t pages = 0;     // pages delivered
  uint64_t bytes = 0;     // bytes delivered
  uint64_t syscalls = 0;  // read_at calls, including retries after EINTR and short reads
};

class PageFile {
 public:
  struct Options {
    size_t page_size = 4096;    // REQUIRES: a power of two >= 512
    bool bypass_cache = false;  // O_DIRECT, else drop-behind; see FileReadSource
    uint32_t read_latency_us = 0;  // > 0: every read waits this long first (DelayedReadSource)
    double read_bandwidth_mbit = 0.0;  // > 0: and as long as its bytes take at this rate
  };

  // Opens `path` read-only: a file, or a URL (http://..., an HttpReadSource; bypass_cache has no
  // meaning there). Throws Error naming the path on failure.
  PageFile(const std::string& path, Options options);
  // Reads through `source` (tests: a FaultInjectingSource).
  PageFile(std::unique_ptr<ReadSource> source, size_t page_size);

  // Reads pages [first_page, first_page + page_count) into `dst`, which must hold
  // page_count * page_size() bytes; any alignment (unaligned buffers go through a bounce buffer
  // when the source needs alignment). Retries EINTR, continues after short reads. Throws Error
  // naming the file and byte offset on an I/O error or when the file ends inside the range.
  void read(uint64_t first_page, uint64_t page_count, void* dst);

  size_t page_size() const { return page_size_; }
  uint64_t page_count() const { return source_->size() / page_size_; }
  uint64_t size_bytes() const { return source_->size(); }
  const std::string& name() const { return source_->name(); }
  // The bypass mode actually active (kNone for sources other than FileReadSource).
  CacheBypass bypass_mode() const { return mode_; }

  PageFileCounters counters() const;
  void reset_counters();

 private:
  void read_exact(uint64_t offset, size_t bytes, std::byte* dst);

  std::unique_ptr<ReadSource> source_;
  size_t page_size_;
  CacheBypass mode_ = CacheBypass::kNone;
  std::atomic<uint64_t> requests_{0}, pages_{0}, bytes_{0}, syscalls_{0};
};

// A buffer aligned to `alignment` bytes (posix_memalign), for O_DIRECT reads.
struct AlignedFree {
  void operator()(void* p) const;
};
using AlignedBuffer = std::unique_ptr<std::byte, AlignedFree>;
AlignedBuffer make_aligned_buffer(size_t bytes, size_t alignment = 4096);

}  // namespace cellwalk
