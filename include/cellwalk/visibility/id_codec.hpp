// Codecs for sorted object-id sets and Δs behind one interface: vLOD §2.4 (digest 001 §3.4 and
// §7, "Codecs behind one interface"). The paper's gap and run codes with its delimiter VLC (our
// unambiguous decoder), zstd in place of its adaptive Huffman for large Δs, Elias–Fano as the
// modern baseline, and the LEB128 gap varints cellwalk stores today. Byte layouts:
// docs/format.md, "Id-set codecs".
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace cellwalk::visibility {

// kVarintGaps:  count, first id, then id − previous − 1, each a LEB128 varint (set_codec.hpp).
// kDelimiterVlc: the gaps id − previous (the first id + 1) in vLOD's delimiter VLC.
// kRunsVlc:     vLOD's RLE: runs of consecutive ids as (offset, length) pairs in the VLC.
// kZstd:        the kVarintGaps record compressed by zstd (the stand-in for adaptive Huffman).
// kEliasFano:   Elias–Fano over [0, last id]: at most 2 + ceil(log2(universe / count)) bits per
//               id whatever the gaps, the size-optimal modern baseline (Stream VByte is the
//               speed one; its sizes are within a few percent of varints', so it would tell a
//               size report nothing new).
enum class IdCodec { kVarintGaps, kDelimiterVlc, kRunsVlc, kZstd, kEliasFano };
inline constexpr IdCodec kIdCodecs[] = {IdCodec::kVarintGaps, IdCodec::kDelimiterVlc,
                                        IdCodec::kRunsVlc, IdCodec::kZstd, IdCodec::kEliasFano};

// "varint", "vlc", "runs-vlc", "zstd", "elias-fano".
std::string id_codec_name(IdCodec codec);
std::vector<std::string> id_codec_names();
// Throws Error listing id_codec_names() for an unknown name.
IdCodec parse_id_codec(const std::string& name);

// Appends one self-delimiting record of `ids` to `out`, so records can be concatenated and read
// back in order with decode_ids. Throws Error when ids are not strictly ascending.
void encode_ids(IdCodec codec, std::span<const uint32_t> ids, std::vector<uint8_t>& out);

// Reads the record at `pos` written by encode_ids with the same codec and advances `pos` past
// it. Returns strictly ascending ids, all < id_limit (the world's object count; ids are 32-bit,
// so a larger limit means 2^32). Throws Error naming `where` and the byte offset when the record
// is truncated or damaged or an id is out of range. Allocates no more than the record's bytes
// can hold (for kZstd: the most any zstd frame of its size can inflate to, 32768 bytes per
// byte), except that a run (kRunsVlc) costs a few bits whatever its length: there the bound is
// id_limit ids, so a damaged record can cost as much memory as the set of every object.
std::vector<uint32_t> decode_ids(IdCodec codec, std::span<const uint8_t> bytes, size_t& pos,
                                 const std::string& where, uint64_t id_limit);

// The bytes encode_ids appends for `ids`.
uint64_t encoded_size(IdCodec codec, std::span<const uint32_t> ids);

// ---- The delimiter VLC at bit level (vLOD §2.4; digest 001 §3.4, "[ours]") -----------------

// The stream of `numbers` (each >= 1), one bool per bit, first bit first: each number's binary
// digits from the most significant, with a 0 stuffed after every two consecutive 1s and one
// more 1 when the stuffed number ends in 1; numbers joined by the delimiter 11. A number v
// costs these bits plus the 2 of its delimiter (1 → 4, 2 → 4, 3 → 5, 100 → 10), the stream
// that sum less 2. Throws Error for a number 0.
std::vector<bool> encode_vlc(std::span<const uint64_t> numbers);
// The inverse, given the count the stream holds (the stream does not say; records store it).
// Throws Error naming `where` when the stream does not hold exactly `count` numbers or one
// overflows 64 bits.
std::vector<uint64_t> decode_vlc(const std::vector<bool>& stream, uint64_t count,
                                 const std::string& where);

}  // namespace cellwalk::visibility
