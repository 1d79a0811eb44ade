// Tests of the visible-set codec (vLOD §2.3–§2.4): gap varints round-trip, Δs between sets,
// damaged input gives Error, sizes against the bitmask.
#include "visibility/set_codec.hpp"

#include <gtest/gtest.h>

#include <set>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/random.hpp"

namespace cellwalk::visibility {
namespace {

std::vector<ObjectId> random_set(Random& rng, uint32_t universe, double density) {
  std::vector<ObjectId> ids;
  for (uint32_t i = 0; i < universe; ++i)
    if (rng.chance(density)) ids.push_back(i);
  return ids;
}

TEST(SetCodec, VarintsRoundTripAtBoundaries) {
  for (uint64_t v : {0ull, 1ull, 127ull, 128ull, 16383ull, 16384ull, 0xFFFFFFFFull, ~0ull}) {
    std::vector<uint8_t> bytes;
    put_varint(bytes, v);
    size_t pos = 0;
    EXPECT_EQ(get_varint(bytes, pos, "test"), v);
    EXPECT_EQ(pos, bytes.size());
  }
}

TEST(SetCodec, SetsRoundTripAndBeatTheBitmaskWhenSparse) {
  Random rng(3);
  for (double density : {0.0, 0.01, 0.1, 0.5, 1.0}) {
    const std::vector<ObjectId> ids = random_set(rng, 5000, density);
    std::vector<uint8_t> bytes;
    append_set(bytes, ids);
    size_t pos = 0;
    EXPECT_EQ(read_set(bytes, pos, "test", 5000), ids);
    EXPECT_EQ(pos, bytes.size());
    // One byte per gap below 128, two below 16384: dense sets cost about one byte per id.
    EXPECT_LE(bytes.size(), 2 * ids.size() + 3);
    if (density >= 0.1) {
      EXPECT_LE(bytes.size(), ids.size() + 3);
    }
    if (density <= 0.1) {
      EXPECT_LT(bytes.size(), bitmask_bytes(5000));
    }
  }
}

TEST(SetCodec, DeltasReconstructTheNeighboursSet) {
  Random rng(5);
  for (int trial = 0; trial < 50; ++trial) {
    const std::vector<ObjectId> a = random_set(rng, 800, 0.2), b = random_set(rng, 800, 0.2);
    const SetDelta d = set_delta(a, b);
    EXPECT_EQ(apply_delta(a, d), b);
    std::vector<uint8_t> bytes;
    append_delta(bytes, d);
    size_t pos = 0;
    const SetDelta back = read_delta(bytes, pos, "test", 800);
    EXPECT_EQ(back.added, d.added);
    EXPECT_EQ(back.removed, d.removed);
    // Reverse direction by swapping added and removed (vLOD stores one Δ per face).
    EXPECT_EQ(apply_delta(b, SetDelta{d.removed, d.added}), a);
  }
}

TEST(SetCodec, DamagedInputGivesErrorNotCrash) {
  std::vector<uint8_t> bytes;
  append_set(bytes, std::vector<ObjectId>{1, 5, 900});
  for (size_t cut = 0; cut < bytes.size(); ++cut) {
    size_t pos = 0;
    EXPECT_THROW(read_set(std::span(bytes).first(cut), pos, "test", 1000), Error);
  }
  size_t pos = 0;
  EXPECT_THROW(read_set(bytes, pos, "test", 900), Error);  // id 900 is out of range
  const std::vector<uint8_t> huge_count = {0xFF, 0xFF, 0xFF, 0xFF, 0x0F, 0x01};
  pos = 0;
  EXPECT_THROW(read_set(huge_count, pos, "test", 1000), Error);
  const std::vector<uint8_t> endless(12, 0xFF);
  pos = 0;
  EXPECT_THROW(get_varint(endless, pos, "test"), Error);
}

TEST(SetCodec, BitmasksRoundTripAndRejectStrayBits) {
  Random rng(7);
  for (uint32_t universe : {1u, 7u, 8u, 9u, 5000u})
    for (double density : {0.0, 0.3, 1.0}) {
      const std::vector<ObjectId> ids = random_set(rng, universe, density);
      std::vector<uint8_t> bytes{0xAB};  // appends after what is there
      append_bitmask(bytes, ids, universe);
      ASSERT_EQ(bytes.size(), 1 + bitmask_bytes(universe));
      size_t pos = 1;
      EXPECT_EQ(read_bitmask(bytes, pos, "test", universe), ids);
      EXPECT_EQ(pos, bytes.size());
      size_t cut = 1;
      EXPECT_THROW(read_bitmask(std::span(bytes).first(bytes.size() - 1), cut, "test", universe), Error);
      if (universe % 8 != 0) {  // a bit past the last object
        bytes.back() |= uint8_t(0x80);
        pos = 1;
        EXPECT_THROW(read_bitmask(bytes, pos, "test", universe), Error);
      }
    }
}

TEST(SetCodec, RandomBytesNeverCrash) {
  Random rng(11);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<uint8_t> bytes(size_t(rng.integer(0, 40)));
    for (uint8_t& b : bytes) b = uint8_t(rng.integer(0, 255));
    size_t pos = 0;
    try {
      const SetDelta d = read_delta(bytes, pos, "fuzz", 1 << 16);
      EXPECT_TRUE(std::is_sorted(d.added.begin(), d.added.end()));
      EXPECT_EQ(std::set<ObjectId>(d.added.begin(), d.added.end()).size(), d.added.size());
    } catch (const Error&) {
    }
  }
}

}  // namespace
}  // namespace cellwalk::visibility
