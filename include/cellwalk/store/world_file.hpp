// The world file: one file of fixed-size pages that `cellwalk build` writes and every strategy
// reads through the store. A header page, named sections each starting on a page boundary, a
// table of per-page checksums and a section table. Byte layout in docs/format.md, "World file".
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace cellwalk {

constexpr uint32_t kDefaultPageSize = 4096;

// Whether `path` starts with the world file's magic (false for an unreadable file; a URL whose
// server cannot be reached throws Error, naming it).
bool is_world_file(const std::string& path);

struct SectionInfo {
  std::string name;         // at most 23 bytes
  uint64_t first_page = 0;  // pages [first_page, first_page + page_count()) hold the section
  uint64_t bytes = 0;       // length without the zero padding of its last page
  uint64_t page_count(uint32_t page_size) const { return (bytes + page_size - 1) / page_size; }
};

// Writes a world file section by section. Memory: one page of buffer plus 4 bytes per page
// for the checksum table. Nothing exists under `path` until finish() has renamed the complete
// file into place; an existing world file there survives any failure.
class WorldWriter {
 public:
  // REQUIRES: page_size is a power of two in [512, 1 MiB].
  WorldWriter(std::string path, uint32_t page_size = kDefaultPageSize);
  ~WorldWriter();

  // REQUIRES: no section is open; names are unique.
  void begin_section(const std::string& name);
  void write(std::span<const uint8_t> bytes);
  // Bytes written into the open section so far: the offset the next write() lands at.
  uint64_t section_offset() const;
  void end_section();
  void finish();

  uint32_t page_size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk

namespace cellwalk {

class PageFile;

// Reads a world file's structure and verified bytes of its sections. Opening checks the header,
// the checksum table and the section table; every page read afterwards is checked against its
// checksum. Damage gives one Error naming the file, the section and the byte offset.
// Thread-safety: read() may be called concurrently.
class WorldFile {
 public:
  struct Options {
    bool bypass_cache = false;  // read around the OS page cache (O_DIRECT or drop-behind)
    uint32_t read_latency_us = 0;  // a slow disk: each read waits this long first (experiments)
    double read_bandwidth_mbit = 0.0;  // a slow link: and as long as its bytes take at this rate
  };
  // `path` is a file or a URL (http://host:port/path.cww, read by range requests).
  WorldFile(const std::string& path, Options options);
  ~WorldFile();

  const std::string& path() const { return path_; }
  uint32_t page_size() const { return page_size_; }
  uint64_t page_count() const { return page_count_; }
  const std::vector<SectionInfo>& sections() const { return sections_; }
  bool has_section(const std::string& name) const;
  // Throws Error naming the file if the section is missing.
  const SectionInfo& section(const std::string& name) const;

  // Bytes [offset, offset + length) of a section, from verified pages.
  std::vector<uint8_t> read(const SectionInfo& section, uint64_t offset, uint64_t length) const;
  std::vector<uint8_t> read_all(const std::string& section) const;

  // Reads and checks every page of the file. Returns the number of pages checked; throws on
  // the first damaged one.
  uint64_t verify(const std::function<void(uint64_t, uint64_t)>& progress = {}) const;

  PageFile& pages() const { return *pages_; }
  // Memory held for the checksum and section tables, counted against a run's budget.
  uint64_t resident_bytes() const;

 private:
  void check_page(uint64_t page, std::span<const uint8_t> bytes) const;
  std::string locate(uint64_t page) const;  // "section X@offset" for messages

  std::string path_;
  std::unique_ptr<PageFile> pages_;
  uint32_t page_size_ = 0;
  uint64_t page_count_ = 0;
  uint64_t checksum_first_page_ = 0;
  std::vector<uint32_t> page_checksums_;  // of pages 1 .. page_checksums_.size()
  std::vector<SectionInfo> sections_;
};

}  // namespace cellwalk
