// Bit-level reading and writing for the id-set codecs (id_codec.cpp, delimiter_vlc.cpp): bits
// go most significant first within each byte; the last byte is padded with zero bits.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/core/error.hpp"

namespace cellwalk::visibility {

// Appends bits to `out`. REQUIRES: out outlives the writer and nothing else appends to it
// while the writer is in use.
class BitWriter {
 public:
  explicit BitWriter(std::vector<uint8_t>& out) : out_(out) {}
  void put(bool bit) {
    if (used_ % 8 == 0) out_.push_back(0);
    if (bit) out_.back() |= uint8_t(0x80u >> (used_ % 8));
    ++used_;
  }
  // The low `n` bits of value, most significant first. REQUIRES: n <= 64.
  void put_bits(uint64_t value, int n) {
    for (int i = n - 1; i >= 0; --i) put((value >> i) & 1);
  }

 private:
  std::vector<uint8_t>& out_;
  uint64_t used_ = 0;
};

// Reads bits from bytes[pos ...]. Throws Error naming `where` and the byte offset when the
// bytes run out. REQUIRES: bytes and where outlive the reader.
class BitReader {
 public:
  BitReader(std::span<const uint8_t> bytes, size_t pos, const std::string& where)
      : bytes_(bytes), pos_(pos), where_(where) {}
  bool next() {
    if (offset() >= bytes_.size()) error("truncated bit stream");
    const bool bit = (bytes_[offset()] >> (7 - read_ % 8)) & 1;
    ++read_;
    return bit;
  }
  // `n` bits as a number, the first most significant. REQUIRES: n <= 64.
  uint64_t bits(int n) {
    uint64_t value = 0;
    for (int i = 0; i < n; ++i) value = value << 1 | uint64_t(next());
    return value;
  }
  // The byte that holds the next bit.
  size_t offset() const { return pos_ + read_ / 8; }
  // Checks that the rest of the current byte is zero padding; returns the offset after it.
  size_t finish() {
    while (read_ % 8 != 0)
      if (next()) error("padding bits after the codes are not zero");
    return offset();
  }
  [[noreturn]] void error(const std::string& what) const {
    fail(where_ + "@" + std::to_string(offset()), what);
  }

 private:
  std::span<const uint8_t> bytes_;
  size_t pos_;
  const std::string& where_;
  uint64_t read_ = 0;
};

}  // namespace cellwalk::visibility
