// Tests of the mesh codec (src/store/mesh_codec.cpp): round trips on the bunny and random
// meshes within the documented quantisation bound, bytes per triangle, and damaged input
// (every byte flipped, every truncation) giving Error or a valid mesh.
#include "cellwalk/store/mesh_codec.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <random>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/lod/lod.hpp"
#include "cellwalk/core/random.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// The bunny as the store holds it: cache- and fetch-ordered (level 0 of its chain).
const Mesh& stored_bunny() {
  static const Mesh mesh = [] {
    LodParams one_level;
    one_level.min_triangles = size_t(1) << 30;
    return build_lod_chain(import_model(test::cgal_mesh("bunny00.off")).objects.at(0).mesh, one_level)
        .levels[0]
        .mesh;
  }();
  return mesh;
}

// Triangles as index triples in their smallest rotation, sorted: the index codec may rotate
// a triangle (keeping its winding) but not change the set.
std::vector<std::array<uint32_t, 3>> triangles(const Mesh& m) {
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    // The smallest of the three rotations: with a repeated index (a degenerate triangle),
    // rotating to the first smallest index would not be canonical.
    const std::array<uint32_t, 3> tri{m.indices[t], m.indices[t + 1], m.indices[t + 2]};
    out.push_back(std::min({tri, std::array{tri[1], tri[2], tri[0]},
                            std::array{tri[2], tri[0], tri[1]}}));
  }
  std::sort(out.begin(), out.end());
  return out;
}

void expect_round_trip(const Mesh& in, const CodecParams& params) {
  const Mesh out = decode_mesh(encode_mesh(in, params), "test");
  ASSERT_EQ(out.vertex_count(), in.vertex_count());
  EXPECT_EQ(triangles(out), triangles(in));
  EXPECT_EQ(out.colors, in.colors);
  EXPECT_EQ(out.uvs, in.uvs);  // exact
  EXPECT_EQ(out.texture, in.texture);
  ASSERT_EQ(out.normals.size(), in.normals.size());
  const Aabb box = bounds_of(in);
  // The documented bound: half a quantisation step per axis, plus float rounding.
  const Vec3 magnitude = glm::max(glm::abs(box.min), glm::abs(box.max));
  const Vec3 bound = box.size() / float((1 << params.position_bits) - 1) * 0.5f + magnitude * 4e-7f;
  Vec3 worst(0);
  for (size_t i = 0; i < in.vertex_count(); ++i) {
    worst = glm::max(worst, glm::abs(out.positions[i] - in.positions[i]));
  }
  EXPECT_TRUE(glm::all(glm::lessThanEqual(worst, bound)))
      << "worst " << worst.x << " " << worst.y << " " << worst.z << " bound " << bound.x;
  // Octahedral normals: the angle error is at most 2.5 grid steps, a step being
  // 1 / (2^(b-1) - 1) of the octahedron's half-width (1.4 rad was seen at 2 bits).
  const float max_angle = 2.5f / float((1 << (params.normal_bits - 1)) - 1);
  for (size_t i = 0; i < in.normals.size(); ++i) {
    ASSERT_GE(glm::dot(out.normals[i], glm::normalize(in.normals[i])), std::cos(max_angle) - 1e-6f)
        << "vertex " << i;
  }
}

TEST(MeshCodec, BunnyRoundTrip) {
  for (int bits : {16, 12, 8}) {
    for (bool zstd : {false, true}) {
      SCOPED_TRACE("bits " + std::to_string(bits) + (zstd ? " zstd" : ""));
      expect_round_trip(stored_bunny(), {bits, 8, zstd});
    }
  }
  expect_round_trip(stored_bunny(), {16, 16, false});
}

// Bytes per triangle against raw floats (12 B/vertex position + 12 normal + 12 B/triangle).
TEST(MeshCodec, BunnyBytesPerTriangle) {
  const Mesh& m = stored_bunny();
  const double raw = 24.0 * m.vertex_count() + 12.0 * m.triangle_count();
  const double plain = encode_mesh(m, {}).size(), zstd = encode_mesh(m, {16, 8, true}).size();
  const double n = double(m.triangle_count());
  std::printf("bunny: raw %.2f B/tri, codec %.2f B/tri (%.1fx), +zstd %.2f B/tri (%.1fx)\n",
              raw / n, plain / n, raw / plain, zstd / n, raw / zstd);
  EXPECT_LT(plain, raw / 3);
  EXPECT_LE(zstd, plain);
}

Mesh random_mesh(std::mt19937& rng, size_t vertices, size_t triangles, bool attributes) {
  std::uniform_real_distribution<float> u(-50.0f, 50.0f);
  Mesh m;
  for (size_t i = 0; i < vertices; ++i) m.positions.emplace_back(u(rng), u(rng) * 0.01f, u(rng));
  std::uniform_int_distribution<uint32_t> pick(0, uint32_t(vertices - 1));
  for (size_t i = 0; i < triangles * 3; ++i) m.indices.push_back(pick(rng));
  if (attributes) {
    compute_normals(m);
    for (Vec3& n : m.normals) n = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
    for (size_t i = 0; i < vertices; ++i) m.colors.push_back(uint32_t(rng()));
    for (size_t i = 0; i < vertices; ++i) m.uvs.emplace_back(u(rng) * 0.1f, u(rng) * 1e-4f);
    m.texture = rng() % 3 == 0 ? kNoTexture : uint32_t(rng() % 1000);
  }
  return m;
}

TEST(MeshCodec, RandomMeshesRoundTrip) {
  std::mt19937 rng(11);
  for (int i = 0; i < 20; ++i) {
    // Sequenced: the order in which function arguments are evaluated is unspecified.
    const size_t vertices = 1 + rng() % 3000;
    const size_t triangles = rng() % 4000;
    const Mesh m = random_mesh(rng, vertices, triangles, i % 2 == 0);
    const CodecParams p{int(1 + rng() % 16), int(2 + rng() % 15), i % 3 == 0};
    SCOPED_TRACE("mesh " + std::to_string(i));
    expect_round_trip(m, p);
  }
}

// A browser has meshoptimizer's decoders but no zstd: without_zstd gives the bytes encode_mesh
// writes without zstd, exactly (oracle: encoding the same mesh with zstd off), for random meshes
// and a textured box; bytes without zstd come back as they were; damage is an Error.
TEST(MeshCodec, WithoutZstdIsTheEncodingWithoutZstd) {
  std::mt19937 rng(12);
  std::vector<Mesh> meshes;
  for (int i = 0; i < 8; ++i) meshes.push_back(random_mesh(rng, 1 + rng() % 2000, rng() % 3000, i % 2 == 0));
  Mesh textured = test::box_mesh({Vec3(0), Vec3(1)});
  textured.uvs.assign(textured.vertex_count(), Vec2(0.5f));
  textured.texture = 3;
  meshes.push_back(textured);
  for (const Mesh& m : meshes) {
    const CodecParams plain{int(1 + rng() % 16), int(2 + rng() % 15), false};
    CodecParams packed = plain;
    packed.zstd = true;
    const std::vector<uint8_t> expected = encode_mesh(m, plain);
    const std::vector<uint8_t> zstd = encode_mesh(m, packed);
    ASSERT_NE(zstd, expected);
    EXPECT_EQ(without_zstd(zstd, "test"), expected);
    EXPECT_EQ(without_zstd(expected, "test"), expected);
  }
  std::vector<uint8_t> cut = encode_mesh(textured, {16, 8, true});
  cut.resize(cut.size() - 3);
  EXPECT_THROW(without_zstd(cut, "test"), Error);
}

// Faces of two objects that meet where both boxes end must meet exactly after decoding (a gap
// of one rounding lets rays and rasterised pixels through the seam, docs/surface-occluders.md):
// a vertex at the box's min or max on an axis decodes to exactly that value.
TEST(MeshCodec, BoxExtremesDecodeExactly) {
  Random rng(17);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 lo(float(rng.uniform(-50, 50)), float(rng.uniform(-50, 50)), float(rng.uniform(-50, 50)));
    const Vec3 hi = lo + Vec3(float(rng.uniform(0.1, 40)), float(rng.uniform(0.1, 40)), float(rng.uniform(0.1, 40)));
    const Mesh in = test::box_mesh({lo, hi});
    const Mesh out = decode_mesh(encode_mesh(in), "test");
    ASSERT_EQ(out.vertex_count(), in.vertex_count());
    for (size_t v = 0; v < out.vertex_count(); ++v)
      for (int a = 0; a < 3; ++a)
        ASSERT_EQ(out.positions[v][a], in.positions[v][a]) << "trial " << trial << " axis " << a;
  }
}

TEST(MeshCodec, EmptyAndFlatMeshes) {
  const Mesh empty = decode_mesh(encode_mesh(Mesh{}), "test");
  EXPECT_EQ(empty.vertex_count(), 0u);
  EXPECT_EQ(empty.triangle_count(), 0u);
  Mesh flat = test::box_mesh({Vec3(0, 1, 0), Vec3(1, 1, 1)});  // zero height
  expect_round_trip(flat, {});
}

TEST(MeshCodec, BadParametersAreErrors) {
  const Mesh box = test::box_mesh({Vec3(0), Vec3(1)});
  EXPECT_THROW(encode_mesh(box, {0, 8, false}), Error);
  EXPECT_THROW(encode_mesh(box, {17, 8, false}), Error);
  EXPECT_THROW(encode_mesh(box, {16, 1, false}), Error);
  EXPECT_THROW(decode_mesh(std::vector<uint8_t>{}, "test"), Error);
}

// Decoding either throws Error or gives a mesh validate() accepts; anything else (another
// exception, a crash, a sanitizer report) fails.
void expect_error_or_valid(const std::vector<uint8_t>& bytes) {
  try {
    const Mesh m = decode_mesh(bytes, "damaged");
    validate(m, "damaged");
  } catch (const Error&) {
  }
}

TEST(MeshCodec, EveryByteFlipAndTruncation) {
  Mesh m = test::box_mesh({Vec3(0), Vec3(1)});
  m.colors.assign(m.vertex_count(), rgba8(10, 20, 30));
  m.uvs.assign(m.vertex_count(), Vec2(0.25f, 0.75f));
  m.texture = 2;
  for (bool zstd : {false, true}) {
    const std::vector<uint8_t> good = encode_mesh(m, {16, 8, zstd});
    for (size_t i = 0; i < good.size(); ++i) {
      for (uint8_t mask : {0x01, 0x80, 0xff}) {
        std::vector<uint8_t> bad = good;
        bad[i] ^= mask;
        expect_error_or_valid(bad);
      }
      expect_error_or_valid({good.begin(), good.begin() + i});
    }
    std::vector<uint8_t> longer = good;
    longer.push_back(0);
    EXPECT_THROW(decode_mesh(longer, "test"), Error);
  }
}

TEST(MeshCodec, HugeDeclaredCountsAreRefused) {
  std::vector<uint8_t> bytes = encode_mesh(test::box_mesh({Vec3(0), Vec3(1)}));
  bytes[8] = bytes[9] = bytes[10] = bytes[11] = 0xff;  // vertex count 2^32 - 1
  try {
    decode_mesh(bytes, "test");
    FAIL() << "no Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("decode limit"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cellwalk
