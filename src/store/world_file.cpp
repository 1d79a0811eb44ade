// Reading the world file (docs/format.md, "World file").
#include <xxhash.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/http_read_source.hpp"
#include "cellwalk/store/page_file.hpp"
#include "cellwalk/store/world_file.hpp"
#include "core/bytes.hpp"
#include "store/world_layout.hpp"

namespace cellwalk {
namespace {

// Reads whole pages covering [offset, offset + length) of the file without checks.
std::vector<uint8_t> read_pages(PageFile& file, uint64_t first_page, uint64_t pages) {
  std::vector<uint8_t> bytes(pages * file.page_size());
  file.read(first_page, pages, bytes.data());
  return bytes;
}

}  // namespace

bool is_world_file(const std::string& path) {
  char magic[8] = {};
  if (!is_http_url(path)) {
    std::ifstream(path, std::ios::binary).read(magic, 8);
  } else if (HttpReadSource source(path); source.size() >= 8) {  // an unreachable URL throws
    source.read_at(magic, 8, 0);
  }
  return std::memcmp(magic, world_layout::kMagic, 8) == 0;
}

using world_layout::check_zero_padding;

WorldFile::WorldFile(const std::string& path, Options options) : path_(path) {
  if (std::filesystem::is_directory(path)) fail(path, "is a directory, expected a world file");
  // The header names the page size; read it with the smallest page size first.
  {
    PageFile probe(path, {512, false});
    if (probe.size_bytes() < 512) fail(path, "too short to be a world file (" + std::to_string(probe.size_bytes()) + " bytes)");
    auto first = read_pages(probe, 0, 1);
    auto h = world_layout::decode_header(first, path, probe.size_bytes());
    page_size_ = h.page_size;
  }
  pages_ = std::make_unique<PageFile>(path, PageFile::Options{page_size_, options.bypass_cache, options.read_latency_us,
                                                               options.read_bandwidth_mbit});
  auto header_page = read_pages(*pages_, 0, 1);
  const auto h = world_layout::decode_header(header_page, path, pages_->size_bytes());
  page_count_ = h.page_count;
  checksum_first_page_ = h.checksum_first_page;

  const uint64_t checksum_pages = (h.checksum_bytes + page_size_ - 1) / page_size_;
  auto table = read_pages(*pages_, h.checksum_first_page, checksum_pages);
  if (XXH3_64bits(table.data(), h.checksum_bytes) != h.checksum_hash)
    fail(path + "@" + std::to_string(h.checksum_first_page * page_size_), "page checksum table: checksum mismatch (the file is damaged)");
  check_zero_padding(std::span<const uint8_t>(table).subspan(h.checksum_bytes),
                     h.checksum_first_page * page_size_ + h.checksum_bytes, path, "page checksum table");
  page_checksums_.resize(h.checksummed_pages);
  if (h.checksum_bytes) std::memcpy(page_checksums_.data(), table.data(), h.checksum_bytes);

  const uint64_t section_offset = h.section_first_page * page_size_;
  auto section_pages = read_pages(*pages_, h.section_first_page, (h.section_bytes + page_size_ - 1) / page_size_);
  if (XXH3_64bits(section_pages.data(), h.section_bytes) != h.section_hash)
    fail(path + "@" + std::to_string(section_offset), "section table: checksum mismatch (the file is damaged)");
  check_zero_padding(std::span<const uint8_t>(section_pages).subspan(h.section_bytes), section_offset + h.section_bytes,
                     path, "section table");
  ByteReader r(std::span<const uint8_t>(section_pages).first(h.section_bytes), path, section_offset);
  for (uint32_t i = 0; i < h.section_count; ++i) {
    auto name = r.get<std::array<char, world_layout::kMaxSectionName + 1>>("section name");
    SectionInfo s;
    s.name.assign(name.data(), strnlen(name.data(), name.size()));
    s.first_page = r.get<uint64_t>("section first page");
    s.bytes = r.get<uint64_t>("section bytes");
    if (s.first_page < 1 || s.first_page >= h.checksum_first_page ||
        s.bytes > (h.checksum_first_page - s.first_page) * page_size_)
      fail(path + "@" + std::to_string(section_offset), "section " + s.name + " lies outside the data pages");
    sections_.push_back(s);
  }
}

WorldFile::~WorldFile() = default;

bool WorldFile::has_section(const std::string& name) const {
  for (const SectionInfo& s : sections_)
    if (s.name == name) return true;
  return false;
}

const SectionInfo& WorldFile::section(const std::string& name) const {
  for (const SectionInfo& s : sections_)
    if (s.name == name) return s;
  fail(path_, "has no section \"" + name + "\": it was built by an older cellwalk or without that option; rebuild it");
}

std::string WorldFile::locate(uint64_t page) const {
  for (const SectionInfo& s : sections_)
    if (page >= s.first_page && page < s.first_page + s.page_count(page_size_))
      return "section " + s.name + "@" + std::to_string((page - s.first_page) * page_size_);
  return "page " + std::to_string(page);
}

void WorldFile::check_page(uint64_t page, std::span<const uint8_t> bytes) const {
  if (page == 0 || page > page_checksums_.size()) return;  // header and tables: checked at open
  if (XXH32(bytes.data(), bytes.size(), 0) != page_checksums_[page - 1])
    fail(path_ + "@" + std::to_string(page * page_size_),
         locate(page) + ": page checksum mismatch (the file is damaged; rebuild it or restore a copy)");
}

std::vector<uint8_t> WorldFile::read(const SectionInfo& section, uint64_t offset, uint64_t length) const {
  if (offset + length > section.bytes || offset + length < offset)
    fail(path_, "section " + section.name + ": read of " + std::to_string(length) + " bytes at " +
                    std::to_string(offset) + " past its end (" + std::to_string(section.bytes) + " bytes)");
  if (length == 0) return {};
  const uint64_t first = offset / page_size_, last = (offset + length - 1) / page_size_;
  auto pages = read_pages(*pages_, section.first_page + first, last - first + 1);
  for (uint64_t p = 0; p <= last - first; ++p)
    check_page(section.first_page + first + p, std::span<const uint8_t>(pages).subspan(p * page_size_, page_size_));
  const uint64_t skip = offset - first * page_size_;
  return std::vector<uint8_t>(pages.begin() + static_cast<long>(skip), pages.begin() + static_cast<long>(skip + length));
}

std::vector<uint8_t> WorldFile::read_all(const std::string& name) const {
  const SectionInfo& s = section(name);
  return read(s, 0, s.bytes);
}

uint64_t WorldFile::verify(const std::function<void(uint64_t, uint64_t)>& progress) const {
  constexpr uint64_t kBatch = 256;
  const uint64_t last = page_checksums_.size();
  std::vector<uint8_t> batch;
  for (uint64_t first = 1; first <= last; first += kBatch) {
    const uint64_t n = std::min(kBatch, last - first + 1);
    batch = read_pages(*pages_, first, n);
    for (uint64_t p = 0; p < n; ++p) check_page(first + p, std::span<const uint8_t>(batch).subspan(p * page_size_, page_size_));
    if (progress) progress(first + n - 1, last);
  }
  return last + 1;  // and the header and tables, checked at open
}

uint64_t WorldFile::resident_bytes() const {
  return page_checksums_.size() * sizeof(uint32_t) + sections_.size() * sizeof(SectionInfo);
}

}  // namespace cellwalk
