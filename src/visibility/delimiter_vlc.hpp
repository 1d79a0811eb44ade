// vLOD's delimiter VLC as byte records (vLOD §2.4; digest 001 §3.4, our unambiguous decoder):
// the codes of id_codec.hpp's kDelimiterVlc and kRunsVlc. The bit level is in id_codec.hpp.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace cellwalk::visibility {

// Appends: varint N, then (N > 0) encode_vlc(numbers) followed by the end mark 1110 (the
// decoder's suffix, so a record ends on its own), zero-padded to a byte. REQUIRES: numbers >= 1.
void append_vlc_record(std::vector<uint8_t>& out, std::span<const uint64_t> numbers);
// Reads a record written by append_vlc_record at `pos` and advances `pos` past it. Throws Error
// naming `where` and the byte offset when it is truncated or damaged. Returns at most two
// numbers per byte of the record (each takes at least 4 bits).
std::vector<uint64_t> read_vlc_record(std::span<const uint8_t> bytes, size_t& pos,
                                      const std::string& where);

}  // namespace cellwalk::visibility
