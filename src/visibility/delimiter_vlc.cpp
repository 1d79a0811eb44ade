// vLOD's delimiter VLC (vLOD §2.4): the digest's unambiguous encoder and decoder (digest 001
// §3.4, "[ours]"), at bit level and as byte records.
#include "visibility/delimiter_vlc.hpp"

#include <bit>

#include "cellwalk/core/error.hpp"
#include "cellwalk/visibility/id_codec.hpp"
#include "visibility/bit_stream.hpp"
#include "visibility/set_codec.hpp"

namespace cellwalk::visibility {
namespace {

// The decoder's frame around a stream: "011" before it (a number ending in 0, then a
// delimiter) and "1110" after it (a delimiter, then a number starting 10), so that every number
// of the stream lies between two delimiters.
constexpr bool kSuffix[] = {true, true, true, false};

// One number's binary digits, most significant first, with a 0 after every two consecutive 1s
// and one more 1 if the stuffed digits end in 1; no delimiter.
void put_stuffed(std::vector<bool>& bits, uint64_t number) {
  if (number == 0) fail("encode_vlc", "numbers must be >= 1 (code ids as gaps, the first + 1)");
  int ones = 0;
  for (int i = 63 - std::countl_zero(number); i >= 0; --i) {
    const bool bit = (number >> i) & 1;
    bits.push_back(bit);
    ones = bit ? ones + 1 : 0;
    if (ones == 2) {
      bits.push_back(false);
      ones = 0;
    }
  }
  if (bits.back()) bits.push_back(true);
}

// The digest's decoder on "011" + stream + "1110": reads `count` numbers, then the suffix up to
// its final 0. A run of 1s of length m >= 3 is a boundary: p of its 1s end the current number
// (p = 4: the number's last digit is 1, then the extra 1), s start the next one, and the
// (m − p − s) / 4 between are numbers equal to 1 (each "11" and its delimiter "11"). p + s
// differs mod 4 for each of the four cases, so m alone decides.
// Source: bool next() (throws past its end), [[noreturn]] error(what).
template <class Source>
std::vector<uint64_t> decode_numbers(Source& bits, uint64_t count) {
  static constexpr int kP[4] = {2, 4, 4, 2}, kS[4] = {2, 1, 2, 1};  // by m mod 4
  std::vector<uint64_t> numbers;
  if (count == 0) return numbers;
  uint64_t number = 0;  // the digits read so far; 0 before the stream's first number
  uint64_t run = 2;     // 1s in the current run: the prefix's delimiter starts the first
  const auto digit = [&](bool bit) {
    if (number == 0) bits.error("the VLC stream does not start with a 1");
    if (number >> 63) bits.error("a VLC number overflows 64 bits");
    number = number << 1 | uint64_t(bit);
  };
  for (;; run = 0) {
    while (bits.next()) ++run;  // a maximal run and the 0 that ends it
    if (run < 3) {              // data; after 11 the 0 is stuffed
      for (uint64_t i = 0; i < run; ++i) digit(true);
      if (run != 2) digit(false);
      continue;
    }
    const int p = kP[run % 4], s = kS[run % 4];
    if (number == 0 && p == 4) bits.error("the VLC stream does not start with a 1");
    if (number != 0) {
      if (p == 4) digit(true);
      numbers.push_back(number);
    }
    const uint64_t ones = (run - p - s) / 4;
    if (ones > count - numbers.size()) bits.error("more VLC numbers than the record's count");
    numbers.insert(numbers.end(), ones, 1);
    if (numbers.size() == count) {
      if (s != 1) bits.error("the VLC stream lacks its end mark 1110");
      return numbers;
    }
    number = s == 1 ? 0b10 : 0b11;  // s = 1: the run's 0 is a digit; s = 2: it is stuffed
  }
}

// A stream followed by the decoder's suffix; reading past both throws.
class StreamSource {
 public:
  StreamSource(const std::vector<bool>& stream, const std::string& where)
      : stream_(stream), where_(where) {}
  bool next() {
    if (read_ < stream_.size()) return stream_[read_++];
    if (read_ < stream_.size() + std::size(kSuffix)) return kSuffix[read_++ - stream_.size()];
    error("the VLC stream ends inside a number");
  }
  bool at_end() const { return read_ == stream_.size() + std::size(kSuffix); }
  [[noreturn]] void error(const std::string& what) const {
    fail(where_ + "@bit " + std::to_string(read_), what);
  }

 private:
  const std::vector<bool>& stream_;
  const std::string& where_;
  size_t read_ = 0;
};

}  // namespace

std::vector<bool> encode_vlc(std::span<const uint64_t> numbers) {
  std::vector<bool> bits;
  for (size_t i = 0; i < numbers.size(); ++i) {
    if (i > 0) bits.insert(bits.end(), {true, true});
    put_stuffed(bits, numbers[i]);
  }
  return bits;
}

std::vector<uint64_t> decode_vlc(const std::vector<bool>& stream, uint64_t count,
                                 const std::string& where) {
  StreamSource source(stream, where);
  if (count == 0) {
    if (!stream.empty()) source.error("a VLC stream of no numbers must be empty");
    return {};
  }
  std::vector<uint64_t> numbers = decode_numbers(source, count);
  if (!source.at_end())
    source.error("the VLC stream holds more than " + std::to_string(count) + " numbers");
  return numbers;
}

void append_vlc_record(std::vector<uint8_t>& out, std::span<const uint64_t> numbers) {
  put_varint(out, numbers.size());
  if (numbers.empty()) return;
  BitWriter writer(out);
  for (bool bit : encode_vlc(numbers)) writer.put(bit);
  for (bool bit : kSuffix) writer.put(bit);
}

std::vector<uint64_t> read_vlc_record(std::span<const uint8_t> bytes, size_t& pos,
                                      const std::string& where) {
  const uint64_t count = get_varint(bytes, pos, where);
  // Each number takes at least 4 bits and the end mark 2 more.
  if (count > 0 && (count > 2 * (bytes.size() - pos) || 4 * count + 2 > 8 * (bytes.size() - pos)))
    fail(where + "@" + std::to_string(pos),
         "VLC record of " + std::to_string(count) + " numbers is longer than its bytes");
  BitReader reader(bytes, pos, where);
  std::vector<uint64_t> numbers = decode_numbers(reader, count);
  pos = reader.finish();
  return numbers;
}

}  // namespace cellwalk::visibility
