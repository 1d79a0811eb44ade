#include "store/world_layout.hpp"

#include <xxhash.h>

#include <algorithm>
#include <array>
#include <cstring>

#include "cellwalk/core/error.hpp"
#include "core/bytes.hpp"

namespace cellwalk::world_layout {

std::vector<uint8_t> encode_header(const Header& h) {
  ByteWriter w;
  w.put(kMagic);
  w.put(h.version);
  w.put(h.page_size);
  w.put(h.page_count);
  w.put(h.checksum_first_page);
  w.put(h.checksummed_pages);
  w.put(h.checksum_bytes);
  w.put(h.checksum_hash);
  w.put(h.section_first_page);
  w.put(h.section_count);
  w.put(uint32_t{0});
  w.put(h.section_bytes);
  w.put(h.section_hash);
  const uint64_t own = XXH3_64bits(w.bytes().data(), w.size());
  w.put(own);
  return std::move(w.bytes());
}

Header decode_header(std::span<const uint8_t> bytes, const std::string& path, uint64_t file_size) {
  ByteReader r(bytes, path, 0);
  if (bytes.size() < kHeaderBytes) r.error("too short to be a world file (" + std::to_string(file_size) + " bytes)");
  if (std::memcmp(bytes.data(), "CWSCENE", 7) == 0)
    r.error("is a scene file, not a world file: build it first (cellwalk build " + path + " -o WORLD.cww) and give the .cww");
  if (std::memcmp(bytes.data(), kMagic, 8) != 0)
    r.error("not a cellwalk world file (bad magic); give a world file made by cellwalk build");
  r.get<std::array<char, 8>>("magic");
  Header h;
  h.version = r.get<uint32_t>("version");
  if (h.version != kVersion)
    fail(path + "@8", "world format version " + std::to_string(h.version) + ", this cellwalk reads " +
                          std::to_string(kVersion) + ": rebuild the world with this cellwalk");
  h.page_size = r.get<uint32_t>("page size");
  h.page_count = r.get<uint64_t>("page count");
  h.checksum_first_page = r.get<uint64_t>("checksum table page");
  h.checksummed_pages = r.get<uint64_t>("checksummed pages");
  h.checksum_bytes = r.get<uint64_t>("checksum table bytes");
  h.checksum_hash = r.get<uint64_t>("checksum table hash");
  h.section_first_page = r.get<uint64_t>("section table page");
  h.section_count = r.get<uint32_t>("section count");
  const uint32_t reserved = r.get<uint32_t>("padding");
  h.section_bytes = r.get<uint64_t>("section table bytes");
  h.section_hash = r.get<uint64_t>("section table hash");
  const uint64_t own = r.get<uint64_t>("header hash");
  if (XXH3_64bits(bytes.data(), kHeaderBytes - 8) != own)
    fail(path + "@0", "header: checksum mismatch (the file is damaged)");
  if (reserved != 0) fail(path + "@68", "header: reserved word is not zero (the file is damaged)");
  check_zero_padding(bytes.subspan(kHeaderBytes), kHeaderBytes, path, "header page");
  if (h.page_size < 512 || (h.page_size & (h.page_size - 1)) != 0)
    fail(path + "@12", "header: page size " + std::to_string(h.page_size) + " is invalid");
  // Page counts are checked against the file before any product, so none can wrap.
  if (file_size % h.page_size != 0 || h.page_count != file_size / h.page_size)
    fail(path, "file has " + std::to_string(file_size) + " bytes but its header says " +
                   std::to_string(h.page_count) + " pages of " + std::to_string(h.page_size) +
                   " (truncated or extended)");
  if (h.checksummed_pages >= h.page_count || h.checksummed_pages + 1 != h.checksum_first_page ||
      h.checksum_bytes != 4 * h.checksummed_pages ||
      h.section_first_page * h.page_size < h.checksum_first_page * h.page_size + h.checksum_bytes ||
      h.section_first_page >= h.page_count || h.section_bytes != h.section_count * kSectionEntryBytes ||
      h.section_first_page * h.page_size + h.section_bytes > file_size)
    fail(path + "@0", "header: table positions are inconsistent (the file is damaged)");
  // The tables follow each other and end the file, as the writer lays them out: no page lies
  // outside the checksummed pages and the tables.
  const auto pages_of = [&h](uint64_t bytes) { return (bytes + h.page_size - 1) / h.page_size; };
  if (h.section_first_page != h.checksum_first_page + pages_of(h.checksum_bytes) ||
      h.page_count != h.section_first_page + pages_of(h.section_bytes))
    fail(path + "@0", "header: the tables do not end the file (the file is damaged)");
  return h;
}

void check_zero_padding(std::span<const uint8_t> padding, uint64_t offset, const std::string& path,
                        const std::string& part) {
  const auto* nonzero = std::find_if(padding.data(), padding.data() + padding.size(), [](uint8_t b) { return b != 0; });
  if (nonzero != padding.data() + padding.size())
    fail(path + "@" + std::to_string(offset + uint64_t(nonzero - padding.data())),
         part + ": padding byte is not zero (the file is damaged; rebuild it or restore a copy)");
}

}  // namespace cellwalk::world_layout
