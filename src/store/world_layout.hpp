// The fixed parts of the world file's layout, shared by its writer and reader.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace cellwalk::world_layout {

constexpr char kMagic[8] = {'C', 'W', 'W', 'O', 'R', 'L', 'D', '1'};
constexpr uint32_t kVersion = 1;
constexpr size_t kMaxSectionName = 23;
constexpr size_t kSectionEntryBytes = 24 + 8 + 8;

struct Header {
  uint32_t version = kVersion;
  uint32_t page_size = 0;
  uint64_t page_count = 0;           // of the whole file
  uint64_t checksum_first_page = 0;  // the table of XXH32 page checksums
  uint64_t checksummed_pages = 0;    // pages 1 .. checksummed_pages are covered
  uint64_t checksum_bytes = 0;
  uint64_t checksum_hash = 0;        // XXH3-64 of the checksum table
  uint64_t section_first_page = 0;
  uint32_t section_count = 0;
  uint64_t section_bytes = 0;
  uint64_t section_hash = 0;         // XXH3-64 of the section table
};

constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 * 6 + 4 + 4 + 8 + 8 + 8;  // fields + own hash

std::vector<uint8_t> encode_header(const Header& header);
// Throws Error naming `path` when the header is damaged, of another version or inconsistent
// with `file_size`, when the tables do not fill the file's last pages exactly as the writer
// lays them out, or when a byte of the header page after the fields (`bytes`: the page, or a
// first part of it) is not zero.
Header decode_header(std::span<const uint8_t> bytes, const std::string& path, uint64_t file_size);

// Padding no checksum covers must be zero, so that every byte of a world file is checked:
// throws Error "<path>@<offset>: <part>: padding byte is not zero ..." at the first byte of
// `padding` that is not, `offset` being the file offset of padding[0].
void check_zero_padding(std::span<const uint8_t> padding, uint64_t offset, const std::string& path,
                        const std::string& part);

}  // namespace cellwalk::world_layout
