// Tests of the id-set codecs (vLOD §2.4; digest 001 §3.4): the delimiter VLC round-trips every
// short sequence and costs what the digest says; every codec returns the set it was given
// (the input is the oracle), records concatenate, damage gives a valid set or an Error.
#include "cellwalk/visibility/id_codec.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <set>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"
#include "visibility/delimiter_vlc.hpp"
#include "visibility/set_codec.hpp"

namespace cellwalk::visibility {
namespace {

constexpr uint64_t kAllIds = uint64_t(1) << 32;

// ---- the VLC at bit level -------------------------------------------------------------------

TEST(DelimiterVlc, RoundTripsEverySequenceOfUpToFourNumbersFrom1To15) {
  std::vector<uint64_t> seq;
  uint64_t sequences = 0;
  const auto all = [&](auto& self, size_t length) -> void {
    const std::vector<bool> stream = encode_vlc(seq);
    ASSERT_EQ(decode_vlc(stream, seq.size(), "test"), seq)
        << "stream of " << stream.size() << " bits";
    ++sequences;
    if (length == 4) return;
    for (uint64_t v = 1; v <= 15; ++v) {
      seq.push_back(v);
      self(self, length + 1);
      seq.pop_back();
    }
  };
  all(all, 0);
  EXPECT_EQ(sequences, 1 + 15 + 15 * 15 + 15 * 15 * 15 + 15 * 15 * 15 * 15);
}

TEST(DelimiterVlc, RoundTripsRandomSequences) {
  Random rng(17);
  for (int trial = 0; trial < 20000; ++trial) {
    std::vector<uint64_t> seq(size_t(rng.integer(1, 24)));
    for (uint64_t& v : seq) {
      const int bits = int(rng.integer(1, 64));  // every magnitude, up to 2^64 − 1
      v = (rng.next() >> (64 - bits)) | (uint64_t(1) << (bits - 1));
      if (rng.chance(0.3)) v = uint64_t(rng.integer(1, 4));  // runs of 1s and 3s stress stuffing
    }
    ASSERT_EQ(decode_vlc(encode_vlc(seq), seq.size(), "test"), seq) << "trial " << trial;
  }
}

TEST(DelimiterVlc, CostsTheDigestsBits) {
  // Digest 001 §3.4: bits per number including its delimiter.
  const std::pair<uint64_t, size_t> costs[] = {{1, 4}, {2, 4}, {3, 5},  {4, 5},
                                               {5, 6}, {7, 7}, {12, 7}, {100, 10}};
  for (const auto& [value, bits] : costs) {
    const std::vector<uint64_t> one{value}, three{value, value, value};
    EXPECT_EQ(encode_vlc(one).size() + 2, bits) << value;  // one number has no delimiter
    EXPECT_EQ(encode_vlc(three).size() + 2, 3 * bits) << value;
  }
}

TEST(DelimiterVlc, WrongCountsAndBadStreamsThrow) {
  const std::vector<uint64_t> seq{1, 5, 3, 100};
  const std::vector<bool> stream = encode_vlc(seq);
  EXPECT_THROW(decode_vlc(stream, 3, "test"), Error);
  EXPECT_THROW(decode_vlc(stream, 5, "test"), Error);
  EXPECT_THROW(decode_vlc(stream, 0, "test"), Error);
  EXPECT_THROW(decode_vlc(std::vector<bool>{false, true}, 1, "test"), Error);  // starts with 0
  EXPECT_THROW(encode_vlc(std::vector<uint64_t>{3, 0}), Error);
  EXPECT_TRUE(decode_vlc({}, 0, "test").empty());
}

TEST(DelimiterVlc, RecordsAreTheCountTheStreamAndTheEndMark) {
  Random rng(19);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<uint64_t> seq(size_t(rng.integer(0, 30)));
    for (uint64_t& v : seq) v = uint64_t(rng.integer(1, 1000));
    std::vector<uint8_t> record, count;
    append_vlc_record(record, seq);
    put_varint(count, seq.size());
    const size_t bits = seq.empty() ? 0 : encode_vlc(seq).size() + 4;
    EXPECT_EQ(record.size(), count.size() + (bits + 7) / 8);
    size_t pos = 0;
    EXPECT_EQ(read_vlc_record(record, pos, "test"), seq);
    EXPECT_EQ(pos, record.size());
  }
}

// ---- the codecs -----------------------------------------------------------------------------

// Each id of [0, universe) with probability `density`; over a large universe, that many
// distinct random draws instead. REQUIRES: density <= 1e-3 when universe > 2^21.
std::vector<uint32_t> random_set(Random& rng, uint64_t universe, double density) {
  if (universe <= (1u << 21)) {
    std::vector<uint32_t> ids;
    for (uint64_t id = 0; id < universe; ++id)
      if (rng.chance(density)) ids.push_back(uint32_t(id));
    return ids;
  }
  std::set<uint32_t> ids;
  while (ids.size() < uint64_t(double(universe) * density))
    ids.insert(uint32_t(rng.integer(0, int64_t(universe) - 1)));
  return {ids.begin(), ids.end()};
}

// `runs` runs of up to `longest` ids each, spread over [0, universe).
std::vector<uint32_t> runs_set(Random& rng, uint64_t universe, int runs, int longest) {
  std::set<uint32_t> ids;
  for (int r = 0; r < runs; ++r) {
    const uint64_t start = uint64_t(rng.integer(0, int64_t(universe) - 1));
    const uint64_t length = uint64_t(rng.integer(1, longest));
    for (uint64_t id = start; id < std::min(universe, start + length); ++id)
      ids.insert(uint32_t(id));
  }
  return {ids.begin(), ids.end()};
}

// Sets of every shape: empty, single, sparse, dense, runs, at the top of the id space.
std::vector<std::vector<uint32_t>> shapes() {
  Random rng(23);
  std::vector<std::vector<uint32_t>> sets = {{},
                                             {0},
                                             {1},
                                             {7},
                                             {0xFFFFFFFF},
                                             {0, 0xFFFFFFFF},
                                             {0xFFFFFFFE, 0xFFFFFFFF},
                                             {0, 1, 2, 3, 4, 5, 6, 7, 8},
                                             {1, 2, 4, 7, 11, 16, 22, 29}};
  std::vector<uint32_t> top;
  for (uint64_t id = kAllIds - 300; id < kAllIds; ++id) top.push_back(uint32_t(id));
  sets.push_back(top);
  for (double density : {0.001, 0.01, 0.1, 0.5, 0.9, 1.0})
    sets.push_back(random_set(rng, 5000, density));
  sets.push_back(random_set(rng, kAllIds, 1e-6));  // ~4300 ids with gaps near 2^20
  for (int trial = 0; trial < 10; ++trial)
    sets.push_back(runs_set(rng, 100000, int(rng.integer(1, 40)), 3000));
  return sets;
}

bool strictly_ascending(const std::vector<uint32_t>& ids) {
  return std::adjacent_find(ids.begin(), ids.end(), std::greater_equal<>()) == ids.end();
}

TEST(IdCodec, NamesParseBackAndUnknownNamesListTheCodecs) {
  for (IdCodec codec : kIdCodecs) EXPECT_EQ(parse_id_codec(id_codec_name(codec)), codec);
  EXPECT_EQ(id_codec_names().size(), std::size(kIdCodecs));
  try {
    parse_id_codec("huffman");
    ADD_FAILURE() << "no Error";
  } catch (const Error& e) {
    for (const std::string& name : id_codec_names())
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << name;
  }
}

TEST(IdCodec, EveryCodecRoundTripsSetsOfEveryShape) {
  for (IdCodec codec : kIdCodecs)
    for (const std::vector<uint32_t>& ids : shapes()) {
      std::vector<uint8_t> bytes{0x5A};  // appends after what is there
      encode_ids(codec, ids, bytes);
      EXPECT_EQ(bytes.size() - 1, encoded_size(codec, ids));
      size_t pos = 1;
      EXPECT_EQ(decode_ids(codec, bytes, pos, "test", kAllIds), ids)
          << id_codec_name(codec) << ", " << ids.size() << " ids";
      EXPECT_EQ(pos, bytes.size()) << id_codec_name(codec);
    }
}

TEST(IdCodec, ConcatenatedRecordsDecodeInOrder) {
  const std::vector<std::vector<uint32_t>> sets = shapes();
  std::vector<uint8_t> bytes;
  for (size_t i = 0; i < sets.size(); ++i)
    for (IdCodec codec : kIdCodecs)
      encode_ids(codec, sets[(i + size_t(codec)) % sets.size()], bytes);
  size_t pos = 0;
  for (size_t i = 0; i < sets.size(); ++i)
    for (IdCodec codec : kIdCodecs)
      ASSERT_EQ(decode_ids(codec, bytes, pos, "test", kAllIds),
                sets[(i + size_t(codec)) % sets.size()])
          << id_codec_name(codec);
  EXPECT_EQ(pos, bytes.size());
}

TEST(IdCodec, UnsortedInputAndIdsPastTheLimitThrow) {
  for (IdCodec codec : kIdCodecs) {
    std::vector<uint8_t> bytes;
    EXPECT_THROW(encode_ids(codec, std::vector<uint32_t>{3, 3}, bytes), Error);
    EXPECT_THROW(encode_ids(codec, std::vector<uint32_t>{4, 3}, bytes), Error);
    encode_ids(codec, std::vector<uint32_t>{5, 899}, bytes);
    size_t pos = 0;
    EXPECT_EQ(decode_ids(codec, bytes, pos, "test", 900).size(), 2u);
    pos = 0;
    EXPECT_THROW(decode_ids(codec, bytes, pos, "test", 899), Error) << id_codec_name(codec);
  }
}

TEST(IdCodec, AbsurdCountsThrowWithoutAllocating) {
  // A varint of 2^40, then a few bytes: no codec may trust it (an allocation would throw
  // bad_alloc, not Error, or exhaust memory).
  std::vector<uint8_t> bytes;
  put_varint(bytes, uint64_t(1) << 40);
  put_varint(bytes, 1000);
  bytes.insert(bytes.end(), 6, 0xFF);
  for (IdCodec codec : kIdCodecs) {
    size_t pos = 0;
    EXPECT_THROW(decode_ids(codec, bytes, pos, "test", kAllIds), Error) << id_codec_name(codec);
  }
}

TEST(IdCodec, ErrorsNameWhereAndTheOffset) {
  for (IdCodec codec : kIdCodecs) {
    std::vector<uint8_t> bytes(3, 0);  // three empty varint sets would be 3 zero bytes
    encode_ids(codec, std::vector<uint32_t>{1, 2, 40, 41, 42, 1000}, bytes);
    const std::span<const uint8_t> cut = std::span(bytes).first(bytes.size() - 1);
    size_t pos = 3;
    try {
      decode_ids(codec, cut, pos, "cell 7", kAllIds);
      ADD_FAILURE() << id_codec_name(codec) << ": no Error";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("cell 7", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find("@"), std::string::npos) << e.what();
    }
  }
}

// Decoding damaged bytes gives a strictly ascending set below the limit, or an Error.
void expect_valid_or_error(IdCodec codec, std::span<const uint8_t> bytes, uint64_t limit) {
  size_t pos = 0;
  try {
    const std::vector<uint32_t> ids = decode_ids(codec, bytes, pos, "damaged", limit);
    EXPECT_TRUE(strictly_ascending(ids)) << id_codec_name(codec);
    EXPECT_TRUE(ids.empty() || ids.back() < limit) << id_codec_name(codec);
    EXPECT_LE(pos, bytes.size());
  } catch (const Error&) {
  }
}

TEST(IdCodec, TruncatedRecordsThrowAndFlippedBitsGiveValidSetsOrErrors) {
  Random rng(29);
  const uint64_t limit = 100000;
  for (IdCodec codec : kIdCodecs)
    for (const std::vector<uint32_t>& ids :
         {std::vector<uint32_t>{42}, random_set(rng, limit, 0.001), runs_set(rng, limit, 6, 50)}) {
      std::vector<uint8_t> bytes;
      encode_ids(codec, ids, bytes);
      for (size_t cut = 0; cut < bytes.size(); ++cut) {
        size_t pos = 0;
        EXPECT_THROW(decode_ids(codec, std::span(bytes).first(cut), pos, "cut", limit), Error)
            << id_codec_name(codec) << " cut at " << cut << " of " << bytes.size();
      }
      for (size_t at = 0; at < bytes.size(); ++at)
        for (int bit = 0; bit < 8; ++bit) {
          std::vector<uint8_t> damaged = bytes;
          damaged[at] ^= uint8_t(1u << bit);
          expect_valid_or_error(codec, damaged, limit);
        }
    }
}

TEST(IdCodec, RandomBytesGiveValidSetsOrErrors) {
  Random rng(31);
  for (IdCodec codec : kIdCodecs)
    for (int trial = 0; trial < 3000; ++trial) {
      std::vector<uint8_t> bytes(size_t(rng.integer(0, 48)));
      for (uint8_t& b : bytes) b = uint8_t(rng.next());
      if (!bytes.empty() && rng.chance(0.5))
        bytes[0] &= 0x0F;  // small counts get past the first check
      expect_valid_or_error(codec, bytes, 1 << 16);
    }
}

// ---- sizes ----------------------------------------------------------------------------------

TEST(IdCodec, RunsVlcBeatsVarintsOnAFewLongRuns) {
  Random rng(37);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<uint32_t> ids = runs_set(rng, 1000000, int(rng.integer(1, 8)), 5000);
    if (ids.size() < 100) continue;
    EXPECT_LT(encoded_size(IdCodec::kRunsVlc, ids), encoded_size(IdCodec::kVarintGaps, ids));
  }
}

TEST(IdCodec, EliasFanoTakesAtMostTwoPlusCeilLog2BitsPerId) {
  Random rng(41);
  for (uint64_t universe : {uint64_t(100), uint64_t(5000), uint64_t(1000000), kAllIds})
    for (double density : {1e-5, 1e-3, 0.01, 0.3, 1.0}) {
      if (universe == kAllIds && density > 1e-5) continue;  // millions of ids; slow to draw
      const std::vector<uint32_t> ids = random_set(rng, universe, density);
      if (ids.empty()) continue;
      std::vector<uint8_t> header;
      put_varint(header, ids.size());
      put_varint(header, ids.back());
      const double n = double(ids.size()), u = double(ids.back()) + 1;
      const double bits = n * (2 + std::ceil(std::log2(std::max(1.0, u / n))));
      EXPECT_LE(encoded_size(IdCodec::kEliasFano, ids),
                header.size() + uint64_t(std::ceil(bits / 8)));
    }
}

}  // namespace
}  // namespace cellwalk::visibility
