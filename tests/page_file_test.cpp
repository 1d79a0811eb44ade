// Tests of PageFile: byte-exact reads against std::ifstream, exact counters, cache-bypass modes,
// and failures injected through FaultInjectingSource (LevelDB's fault_injection_test idea).
#include "cellwalk/store/page_file.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "cellwalk/core/error.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

std::vector<char> random_bytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<char> bytes(n);
  for (char& b : bytes) b = static_cast<char>(rng());
  return bytes;
}

std::string write_file(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

std::vector<char> read_with_ifstream(const std::string& path, uint64_t offset, size_t n) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  std::vector<char> bytes(n);
  in.read(bytes.data(), static_cast<std::streamsize>(n));
  EXPECT_EQ(static_cast<size_t>(in.gcount()), n);
  return bytes;
}

std::string page_file_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Random page ranges, read into buffers at random (mostly unaligned) addresses.
void expect_reads_match(PageFile& file, const std::string& path, uint32_t seed, int reads) {
  std::mt19937 rng(seed);
  const uint64_t pages = file.page_count();
  uint64_t expected_pages = 0;
  for (int i = 0; i < reads; ++i) {
    const uint64_t first = rng() % pages;
    const uint64_t count = 1 + rng() % std::min<uint64_t>(8, pages - first);
    const size_t bytes = count * file.page_size();
    std::vector<char> buffer(bytes + 64);
    char* dst = buffer.data() + rng() % 64;
    file.read(first, count, dst);
    ASSERT_EQ(std::vector<char>(dst, dst + bytes),
              read_with_ifstream(path, first * file.page_size(), bytes))
        << "pages " << first << "+" << count;
    expected_pages += count;
  }
  const PageFileCounters c = file.counters();
  EXPECT_EQ(c.requests, static_cast<uint64_t>(reads));
  EXPECT_EQ(c.pages, expected_pages);
  EXPECT_EQ(c.bytes, expected_pages * file.page_size());
}

TEST(PageFile, ReadsExactlyWhatIfstreamReadsAndCountsExactly) {
  test::TempDir dir;
  for (size_t page_size : {512u, 4096u, 16384u}) {
    const std::string path = write_file(dir.file("f" + std::to_string(page_size)),
                                        random_bytes(page_size * 37, 7));
    PageFile file(path, {.page_size = page_size, .bypass_cache = false});
    EXPECT_EQ(file.bypass_mode(), CacheBypass::kNone);
    EXPECT_EQ(file.page_count(), 37u);
    expect_reads_match(file, path, 11, 200);
    file.reset_counters();
    EXPECT_EQ(file.counters().requests, 0u);
    EXPECT_EQ(file.counters().bytes, 0u);
  }
}

// A slow disk (issue 18's experiments): the same bytes, and every read system call waits at
// least the latency first (a lower bound only: a sleep never ends early).
TEST(PageFile, InjectedLatencyDelaysEveryReadAndChangesNoByte) {
  test::TempDir dir;
  const std::string path = write_file(dir.file("slow"), random_bytes(4096 * 16, 9));
  PageFile file(path, {.page_size = 4096, .bypass_cache = false, .read_latency_us = 4000});
  expect_reads_match(file, path, 3, 10);
  const uint64_t calls = file.counters().syscalls;
  EXPECT_GE(calls, 10u);
  std::vector<char> page(4096);
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 5; ++i) file.read(uint64_t(i), 1, page.data());
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(ms, 5 * 4.0);
  EXPECT_EQ(file.counters().syscalls, calls + 5);
}

// O_DIRECT where the file system takes it, else drop-behind; either way the bytes are exact.
void expect_bypass_works(const std::filesystem::path& folder) {
  const std::string path = (folder / ("cellwalk-bypass-" + std::to_string(getpid()))).string();
  write_file(path, random_bytes(4096 * 64, 3));
  {
    PageFile file(path, {.page_size = 4096, .bypass_cache = true});
    std::cout << "[          ] cache bypass on " << folder << ": " << to_string(file.bypass_mode())
              << "\n";
    ::testing::Test::RecordProperty("bypass_mode_" + folder.filename().string(),
                                    to_string(file.bypass_mode()));
    EXPECT_NE(file.bypass_mode(), CacheBypass::kNone);
    expect_reads_match(file, path, 5, 300);
    // An aligned destination is read in place.
    AlignedBuffer aligned = make_aligned_buffer(4096 * 4);
    file.read(10, 4, aligned.get());
    const std::vector<char> expected = read_with_ifstream(path, 10 * 4096, 4096 * 4);
    EXPECT_EQ(0, std::memcmp(aligned.get(), expected.data(), expected.size()));
  }
  std::filesystem::remove(path);
}

TEST(PageFile, BypassModeWorksOnTmp) { expect_bypass_works(std::filesystem::temp_directory_path()); }

TEST(PageFile, BypassModeWorksOnTmpfs) {
  if (!std::filesystem::is_directory("/dev/shm")) GTEST_SKIP() << "no /dev/shm";
  expect_bypass_works("/dev/shm");
}

TEST(PageFile, ConcurrentReadersGetExactBytesAndCounters) {
  test::TempDir dir;
  const std::string path = write_file(dir.file("f"), random_bytes(4096 * 128, 9));
  PageFile file(path, {.page_size = 4096, .bypass_cache = true});
  const std::vector<char> all = read_with_ifstream(path, 0, 4096 * 128);
  std::vector<std::thread> threads;
  std::atomic<int> mismatches{0};
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      std::mt19937 rng(t);
      std::vector<char> page(4096);
      for (int i = 0; i < 500; ++i) {
        const uint64_t p = rng() % 128;
        file.read(p, 1, page.data());
        if (std::memcmp(page.data(), all.data() + p * 4096, 4096) != 0) ++mismatches;
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(mismatches, 0);
  EXPECT_EQ(file.counters().requests, 2000u);
  EXPECT_EQ(file.counters().pages, 2000u);
}

TEST(PageFile, RejectsBadPageSizesAndMissingFilesAndReadsPastTheEnd) {
  test::TempDir dir;
  const std::string path = write_file(dir.file("f"), random_bytes(4096 * 4 + 100, 1));
  EXPECT_NE(page_file_error([&] { PageFile(path, {.page_size = 1000}); }).find("power of two"),
            std::string::npos);
  EXPECT_NE(page_file_error([&] { PageFile(path, {.page_size = 256}); }).find("power of two"),
            std::string::npos);
  EXPECT_NE(page_file_error([&] { PageFile(dir.file("missing"), {}); }).find("missing"), std::string::npos);
  PageFile file(path, {});
  EXPECT_EQ(file.page_count(), 4u);  // the partial tail is not a page
  std::vector<char> buffer(4096 * 2);
  const std::string message = page_file_error([&] { file.read(3, 2, buffer.data()); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("@ byte 12288"), std::string::npos) << message;
  EXPECT_EQ(file.counters().requests, 0u);
}

struct FaultyFile {
  explicit FaultyFile(const test::TempDir& dir, bool bypass = false)
      : path(write_file(dir.file("faulty"), random_bytes(4096 * 16, 21))) {
    auto source = std::make_unique<FaultInjectingSource>(
        std::make_unique<FileReadSource>(path, bypass, 4096));
    faults = source.get();
    file = std::make_unique<PageFile>(std::move(source), 4096);
  }
  std::string path;
  FaultInjectingSource* faults = nullptr;
  std::unique_ptr<PageFile> file;
};

TEST(PageFile, IoErrorNamesFileAndOffset) {
  test::TempDir dir;
  FaultyFile f(dir);
  f.faults->add_rule({.begin = 5 * 4096 + 10, .end = 5 * 4096 + 11, .fault = FaultInjectingSource::Fault::kError, .error_number = EIO});
  std::vector<char> buffer(4096 * 8);
  f.file->read(0, 5, buffer.data());  // pages 0-4 do not touch the faulty byte
  const std::string message = page_file_error([&] { f.file->read(2, 4, buffer.data()); });
  EXPECT_NE(message.find(f.path), std::string::npos) << message;
  EXPECT_NE(message.find("@ byte 8192"), std::string::npos) << message;
  EXPECT_NE(message.find("errno 5"), std::string::npos) << message;
  EXPECT_EQ(f.file->counters().requests, 1u);  // the failed read is not counted as delivered
}

TEST(PageFile, ShortReadsAndInterruptsAreRetriedToExactBytes) {
  test::TempDir dir;
  FaultyFile f(dir);
  f.faults->add_rule({.begin = 0, .end = 4096 * 16, .fault = FaultInjectingSource::Fault::kShort, .short_bytes = 1000, .remaining = 5});
  f.faults->add_rule({.begin = 0, .end = 4096 * 16, .fault = FaultInjectingSource::Fault::kInterrupt, .remaining = 3});
  std::vector<char> buffer(4096 * 3);
  f.file->read(4, 3, buffer.data());
  EXPECT_EQ(buffer, read_with_ifstream(f.path, 4 * 4096, 4096 * 3));
  // 5 short reads of 1000 bytes, then 3 interrupts, then one read of the remaining 7288 bytes.
  EXPECT_EQ(f.file->counters().syscalls, 9u);
  EXPECT_EQ(f.file->counters().requests, 1u);
  EXPECT_EQ(f.file->counters().bytes, 4096u * 3);
}

TEST(PageFile, ShortReadsUnderODirectRestartAtWholePages) {
  test::TempDir dir;
  FaultyFile f(dir, /*bypass=*/true);
  f.faults->add_rule({.begin = 0, .end = 4096 * 16, .fault = FaultInjectingSource::Fault::kShort, .short_bytes = 4096 + 1000, .remaining = 2});
  std::vector<char> buffer(4096 * 4);
  f.file->read(8, 4, buffer.data());
  EXPECT_EQ(buffer, read_with_ifstream(f.path, 8 * 4096, 4096 * 4));
}

TEST(PageFile, EndlessInterruptsOrShortReadsFailInsteadOfHanging) {
  test::TempDir dir;
  FaultyFile f(dir, /*bypass=*/true);
  f.faults->add_rule({.begin = 4096 * 2, .end = 4096 * 3, .fault = FaultInjectingSource::Fault::kShort, .short_bytes = 100});
  std::vector<char> buffer(4096 * 2);
  const std::string message = page_file_error([&] { f.file->read(1, 2, buffer.data()); });
  if (f.faults->alignment() > 1) {
    // 100-byte reads never complete a page under O_DIRECT.
    EXPECT_NE(message.find("no progress"), std::string::npos) << message;
  } else {
    EXPECT_EQ(message, "");  // byte-granular sources make progress
  }
}

}  // namespace
}  // namespace cellwalk
