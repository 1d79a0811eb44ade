// Little-endian byte encoding for cellwalk's files. ByteReader checks every read against the
// end of its buffer and reports where a damaged input ends too soon, so parsers built on it
// cannot read out of bounds.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "cellwalk/core/error.hpp"

namespace cellwalk {

static_assert(std::endian::native == std::endian::little, "cellwalk files are little-endian");

class ByteWriter {
 public:
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  template <typename T>
  void put_array(std::span<const T> values) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(values.data());
    bytes_.insert(bytes_.end(), p, p + values.size_bytes());
  }
  void put_string(std::string_view s) {
    put(static_cast<uint32_t>(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  std::vector<uint8_t>& bytes() { return bytes_; }
  size_t size() const { return bytes_.size(); }
  void clear() { bytes_.clear(); }

 private:
  std::vector<uint8_t> bytes_;
};

// Reads from a buffer that came from `where` starting at file offset `base`; errors name
// "<where>@<offset>".
class ByteReader {
 public:
  ByteReader(std::span<const uint8_t> bytes, std::string where, uint64_t base = 0)
      : bytes_(bytes), where_(std::move(where)), base_(base) {}

  template <typename T>
  T get(std::string_view what) {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  // Reads `count` elements; checks the count against the bytes left before allocating.
  template <typename T>
  std::vector<T> get_array(uint64_t count, std::string_view what) {
    if (count > remaining() / sizeof(T)) too_short(count * sizeof(T), what);
    std::vector<T> values(count);
    if (count == 0) return values;  // memcpy's pointers must not be null, even for 0 bytes
    std::memcpy(values.data(), bytes_.data() + pos_, count * sizeof(T));
    pos_ += count * sizeof(T);
    return values;
  }
  std::string get_string(std::string_view what) {
    uint32_t n = get<uint32_t>(what);
    need(n, what);
    std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  size_t remaining() const { return bytes_.size() - pos_; }
  uint64_t offset() const { return base_ + pos_; }
  [[noreturn]] void error(std::string_view what) const {
    fail(where_ + "@" + std::to_string(offset()), what);
  }

 private:
  void need(uint64_t n, std::string_view what) {
    if (n > remaining()) too_short(n, what);
  }
  [[noreturn]] void too_short(uint64_t n, std::string_view what) const {
    error("truncated: " + std::string(what) + " needs " + std::to_string(n) + " bytes, " +
          std::to_string(remaining()) + " left");
  }

  std::span<const uint8_t> bytes_;
  std::string where_;
  uint64_t base_;
  size_t pos_ = 0;
};

}  // namespace cellwalk
