// Writing the world file (docs/format.md, "World file").
#include <xxhash.h>

#include <cstring>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/store/world_file.hpp"
#include "core/bytes.hpp"
#include "store/world_layout.hpp"

namespace cellwalk {

struct WorldWriter::Impl {
  Impl(std::string path, uint32_t page_size) : file(std::move(path)), page_size(page_size) {
    if (page_size < 512 || page_size > (1u << 20) || (page_size & (page_size - 1)) != 0)
      fail(file.path(), "page size " + std::to_string(page_size) + " is not a power of two in [512, 1 MiB]");
    // Page 0 is the header, written for real by finish() once every field is known.
    file.write(std::vector<uint8_t>(page_size, 0));
  }

  uint64_t next_page() const { return file.size() / page_size; }

  // Appends bytes, checksumming each page as it completes.
  void append(std::span<const uint8_t> bytes) {
    while (!bytes.empty()) {
      const size_t n = std::min<size_t>(bytes.size(), page_size - page.size());
      page.insert(page.end(), bytes.begin(), bytes.begin() + static_cast<long>(n));
      bytes = bytes.subspan(n);
      if (page.size() == page_size) flush_page();
    }
  }
  void pad_to_page() {
    if (!page.empty()) {
      page.resize(page_size, 0);
      flush_page();
    }
  }
  void flush_page() {
    page_checksums.push_back(XXH32(page.data(), page.size(), 0));
    file.write(page);
    page.clear();
  }

  AtomicFile file;
  uint32_t page_size;
  std::vector<uint8_t> page;               // the page being filled
  std::vector<uint32_t> page_checksums;    // of pages 1, 2, ... as written
  std::vector<SectionInfo> sections;
  bool open = false;
  uint64_t open_bytes = 0;
};

WorldWriter::WorldWriter(std::string path, uint32_t page_size)
    : impl_(std::make_unique<Impl>(std::move(path), page_size)) {}
WorldWriter::~WorldWriter() = default;

uint32_t WorldWriter::page_size() const { return impl_->page_size; }

void WorldWriter::begin_section(const std::string& name) {
  if (impl_->open) fail(impl_->file.path(), "internal: section " + name + " begun inside another");
  if (name.empty() || name.size() > world_layout::kMaxSectionName)
    fail(impl_->file.path(), "section name \"" + name + "\" must have 1 to 23 bytes");
  for (const SectionInfo& s : impl_->sections)
    if (s.name == name) fail(impl_->file.path(), "internal: section " + name + " written twice");
  impl_->sections.push_back({name, impl_->next_page(), 0});
  impl_->open = true;
}

void WorldWriter::write(std::span<const uint8_t> bytes) {
  if (!impl_->open) fail(impl_->file.path(), "internal: write outside a section");
  impl_->append(bytes);
  impl_->sections.back().bytes += bytes.size();
}

uint64_t WorldWriter::section_offset() const { return impl_->open ? impl_->sections.back().bytes : 0; }

void WorldWriter::end_section() {
  impl_->pad_to_page();
  impl_->open = false;
}

void WorldWriter::finish() {
  Impl& w = *impl_;
  if (w.open) end_section();
  // The checksum table covers every page before it; the section table follows it, and the
  // header (page 0) holds the checksums of both.
  const uint64_t checksum_page = w.next_page();
  const uint64_t checksummed_pages = w.page_checksums.size();
  ByteWriter table;
  table.put_array(std::span<const uint32_t>(w.page_checksums));
  const uint64_t checksum_bytes = table.size();
  const uint64_t checksum_hash = XXH3_64bits(table.bytes().data(), table.size());
  w.append(table.bytes());
  w.pad_to_page();

  const uint64_t section_page = w.next_page();
  ByteWriter sections;
  for (const SectionInfo& s : w.sections) {
    char name[world_layout::kMaxSectionName + 1] = {};
    std::memcpy(name, s.name.data(), s.name.size());
    sections.put(name);
    sections.put(s.first_page);
    sections.put(s.bytes);
  }
  const uint64_t section_hash = XXH3_64bits(sections.bytes().data(), sections.size());
  const uint64_t section_bytes = sections.size();
  w.append(sections.bytes());
  w.pad_to_page();

  world_layout::Header h;
  h.page_size = w.page_size;
  h.page_count = w.next_page();
  h.checksum_first_page = checksum_page;
  h.checksummed_pages = checksummed_pages;
  h.checksum_bytes = checksum_bytes;
  h.checksum_hash = checksum_hash;
  h.section_first_page = section_page;
  h.section_count = static_cast<uint32_t>(w.sections.size());
  h.section_bytes = section_bytes;
  h.section_hash = section_hash;
  w.file.overwrite(0, world_layout::encode_header(h));
  w.file.commit();
}

}  // namespace cellwalk
