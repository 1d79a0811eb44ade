// Tests of base-colour textures from import to the world file (scene/texture.hpp): decoding
// against the image's own texels, OBJ map_Kd and glTF baseColorTexture against oracles read
// from the files independently, the scene file's texture records and the world's sections.
#include "cellwalk/scene/texture.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <tuple>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/render/image.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/store/world.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using test::TempDir;

// A w × h image whose texel (x, y), counted from the top-left, is (x * 16, y * 16, x + y, 255),
// written as a PNG; returns its bytes.
std::vector<uint8_t> gradient_png(const TempDir& dir, const std::string& name, int w, int h) {
  Image image;
  image.width = w;
  image.height = h;
  image.rgba.resize(size_t(w) * h * 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &image.rgba[(size_t(h - 1 - y) * w + x) * 4];  // Image rows run bottom-up
      p[0] = uint8_t(x * 16), p[1] = uint8_t(y * 16), p[2] = uint8_t(x + y), p[3] = 255;
    }
  write_png(image, dir.file(name));
  return test::slurp(dir.file(name));
}

Rgba8 gradient_texel(uint32_t x, uint32_t y) { return rgba8(uint8_t(x * 16), uint8_t(y * 16), uint8_t(x + y)); }

TEST(Texture, PngDecodesToItsTexelsAndHalvesByABoxFilter) {
  TempDir dir;
  const std::vector<uint8_t> png = gradient_png(dir, "g.png", 8, 6);
  const Texture full = decode_texture(png, "g.png");
  ASSERT_EQ(full.width, 8u);
  ASSERT_EQ(full.height, 6u);
  for (uint32_t y = 0; y < 6; ++y)
    for (uint32_t x = 0; x < 8; ++x) ASSERT_EQ(full.texels[y * 8 + x], gradient_texel(x, y)) << x << "," << y;
  // At most 4 a side: halved once, each texel the mean of its 2 × 2 block.
  const Texture half = decode_texture(png, "g.png", 4);
  ASSERT_EQ(half.width, 4u);
  ASSERT_EQ(half.height, 3u);
  for (uint32_t y = 0; y < 3; ++y)
    for (uint32_t x = 0; x < 4; ++x) {
      uint32_t r = 0, g = 0, b = 0;
      for (uint32_t sy = 2 * y; sy < 2 * y + 2; ++sy)
        for (uint32_t sx = 2 * x; sx < 2 * x + 2; ++sx) {
          r += sx * 16, g += sy * 16, b += sx + sy;
        }
      EXPECT_EQ(half.texels[y * 4 + x], rgba8(uint8_t(r / 4), uint8_t(g / 4), uint8_t(b / 4))) << x << "," << y;
    }
  // An odd side folds its last texel into the last output texel: 5 → 2 covers all five.
  const Texture odd = decode_texture(gradient_png(dir, "o.png", 5, 1), "o.png", 2);
  ASSERT_EQ(odd.width, 2u);
  EXPECT_EQ(odd.texels[1] & 0xff, (2 + 3 + 4) * 16 / 3);
}

TEST(Texture, DamagedOrForeignImagesGiveAnErrorNamingThem) {
  TempDir dir;
  const std::vector<uint8_t> png = gradient_png(dir, "g.png", 8, 6);
  for (size_t n = 0; n < png.size(); n += 7) {
    try {
      const Texture t = decode_texture(std::span(png).first(n), "cut.png");
      EXPECT_EQ(t.texels.size(), size_t(t.width) * t.height);
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("cut.png"), std::string::npos) << e.what();
    }
  }
  const std::vector<uint8_t> text = {'n', 'o', 't', ' ', 'a', 'n', ' ', 'i', 'm', 'a', 'g', 'e'};
  EXPECT_THROW(check_texture(text, "t.txt"), Error);
  EXPECT_THROW(check_texture({}, "empty.png"), Error);
  // A real JPEG (the spider's).
  const Texture jpeg = decode_texture(test::slurp(test::assimp_model("OBJ/SpiderTex.jpg")), "SpiderTex.jpg");
  EXPECT_GT(jpeg.width, 0u);
  EXPECT_EQ(jpeg.texels.size(), size_t(jpeg.width) * jpeg.height);
}

// OBJ: vt with v flipped (cellwalk's v runs down the image), map_Kd beside the model, one object
// per texture when a group shows two, a face without vt or a missing image drawn untextured.
TEST(TextureImport, ObjMapKdAndFlippedTextureCoordinates) {
  TempDir dir;
  const std::vector<uint8_t> a = gradient_png(dir, "a.png", 4, 4), b = gradient_png(dir, "b.png", 2, 2);
  // The truncated PNG's header reads, its pixels do not: import decodes it whole and drops it.
  test::spit(dir.file("cut.png"), {a.begin(), a.begin() + 60});
  std::ofstream(dir.file("m.mtl")) << "newmtl A\nKd 0.5 0.5 0.5\nmap_Kd -s 1 1 1 a.png\nnewmtl B\nmap_Kd .\\b.png\n"
                                      "newmtl Gone\nmap_Kd missing.png\nnewmtl Cut\nmap_Kd cut.png\n";
  std::ofstream(dir.file("m.obj")) << "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                                      "vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n"
                                      "g g\nusemtl A\nf 1/1 2/2 3/3\nusemtl B\nf 2/2 4/4 3/3\n"
                                      "g h\nusemtl A\nf 1 2 3\ng k\nusemtl Gone\nf 1/1 2/2 3/3\n"
                                      "g m\nusemtl A\nf 1/1 2/2 3/3\nf 2 4 3\ng c\nusemtl Cut\nf 1/1 2/2 3/3\n";
  const ImportedModel model = import_model(dir.file("m.obj"));
  ASSERT_EQ(model.textures.size(), 2u);
  EXPECT_EQ(model.textures[0].encoded, a);
  EXPECT_EQ(model.textures[1].encoded, b);
  ASSERT_EQ(model.objects.size(), 7u);
  EXPECT_EQ(model.objects[0].name, "g/A");
  EXPECT_EQ(model.objects[1].name, "g/B");
  EXPECT_EQ(model.objects[0].color, rgba8(128, 128, 128));  // Kd multiplies the texture
  EXPECT_EQ(model.objects[1].color, rgba8(255, 255, 255));  // no Kd: the texture as it is
  // Each corner's uv is its vt's (u, 1 − v): vt k was given for position k here.
  const Vec2 vt[4] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  for (int k = 0; k < 2; ++k) {
    const Mesh& m = model.objects[k].mesh;
    EXPECT_EQ(m.texture, uint32_t(k));
    ASSERT_EQ(m.uvs.size(), m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) {
      const int position = int(m.positions[v].x) + 2 * int(m.positions[v].y);
      EXPECT_EQ(m.uvs[v], Vec2(vt[position].x, 1.0f - vt[position].y));
    }
  }
  EXPECT_EQ(model.objects[2].mesh.texture, kNoTexture);  // no vt
  EXPECT_TRUE(model.objects[2].mesh.uvs.empty());
  EXPECT_EQ(model.objects[3].mesh.texture, kNoTexture);  // its image is missing
  // Group m: its face with vt is textured, its face without is a part of its own, untextured.
  EXPECT_EQ(model.objects[4].name, "m/A");
  EXPECT_EQ(model.objects[4].mesh.texture, 0u);
  EXPECT_EQ(model.objects[4].mesh.triangle_count(), 1u);
  EXPECT_EQ(model.objects[5].mesh.texture, kNoTexture);
  EXPECT_EQ(model.objects[5].mesh.triangle_count(), 1u);
  EXPECT_EQ(model.objects[6].mesh.texture, kNoTexture);  // its image is damaged
  // From memory nothing beside the model is read.
  EXPECT_TRUE(parse_model(ModelFormat::kObj, test::slurp(dir.file("m.obj")), "m.obj").textures.empty());
  // A real file: the spider names its JPEGs as ".\x.jpg".
  const ImportedModel spider = import_model(test::assimp_model("OBJ/spider.obj"));
  EXPECT_EQ(spider.objects.size(), 19u);
  EXPECT_EQ(spider.textures.size(), 4u);
  size_t textured = 0;
  for (const Object& o : spider.objects) textured += o.mesh.texture != kNoTexture;
  EXPECT_EQ(textured, 19u);
}

// glTF: the image bytes from a GLB's buffer view, a .gltf's file beside it and a data URI are
// the same PNG, and the uvs are TEXCOORD_0 as an independent reading of the .gltf's JSON and
// .bin gives them.
TEST(TextureImport, GltfBaseColorTextureFromViewFileAndDataUri) {
  const std::string dir = test::assimp_model("glTF2/BoxTextured-glTF/");
  const std::vector<uint8_t> png = test::slurp(dir + "CesiumLogoFlat.png");
  std::vector<ImportedModel> flavours;
  for (const char* file : {"glTF2/BoxTextured-glTF/BoxTextured.gltf", "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb",
                           "glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf"})
    flavours.push_back(import_model(test::assimp_model(file)));
  for (const ImportedModel& m : flavours) {
    ASSERT_EQ(m.textures.size(), 1u);
    EXPECT_EQ(m.textures[0].encoded, png);
    ASSERT_EQ(m.objects.size(), 1u);
    EXPECT_EQ(m.objects[0].mesh.texture, 0u);
  }
  // The oracle: TEXCOORD_0's accessor read straight from the JSON and the .bin.
  std::ifstream in(dir + "BoxTextured.gltf");
  const nlohmann::json doc = nlohmann::json::parse(in);
  const int accessor = doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"];
  const nlohmann::json& acc = doc["accessors"][accessor];
  const nlohmann::json& view = doc["bufferViews"][int(acc["bufferView"])];
  const std::vector<uint8_t> bin = test::slurp(dir + std::string(doc["buffers"][0]["uri"]));
  const size_t offset = size_t(view.value("byteOffset", 0)) + size_t(acc.value("byteOffset", 0));
  const size_t stride = view.value("byteStride", 8);
  for (const ImportedModel& m : flavours) {
    const Mesh& mesh = m.objects[0].mesh;
    ASSERT_EQ(mesh.uvs.size(), size_t(acc["count"]));
    for (size_t i = 0; i < mesh.uvs.size(); ++i) {
      Vec2 uv;
      std::memcpy(&uv, bin.data() + offset + i * stride, sizeof uv);
      ASSERT_EQ(mesh.uvs[i], uv) << "vertex " << i;
    }
  }
  // Parsed from memory, a data URI is still read: it is inside the file.
  const ImportedModel memory = parse_model(ModelFormat::kGltf, test::slurp(test::assimp_model("glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf")), "e.gltf");
  ASSERT_EQ(memory.textures.size(), 1u);
  EXPECT_EQ(memory.textures[0].encoded, png);
}

Object textured_square(uint32_t texture) {
  Object o;
  o.name = "square";
  o.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  o.mesh.uvs = {{0, 1}, {1, 1}, {0, 0}, {1, 0}};
  o.mesh.indices = {0, 1, 2, 1, 3, 2};
  o.mesh.texture = texture;
  compute_normals(o.mesh);
  o.bounds = bounds_of(o.mesh);
  return o;
}

// The scene file keeps textures as their bytes and meshes' uvs exactly; an object may not name
// a texture not added before it; a damaged texture record is named.
TEST(TextureStore, SceneAndWorldKeepTexturesAndTheLevelsSampleThem) {
  TempDir dir;
  const std::vector<uint8_t> png = gradient_png(dir, "g.png", 16, 8);
  {
    SceneWriter early(dir.file("early.cwscene"));
    EXPECT_THROW(early.add(textured_square(0)), Error);
    EXPECT_THROW(early.add_texture({"text", {'a', 'b', 'c'}}), Error);
  }
  SceneWriter writer(dir.file("t.cwscene"));
  writer.add_texture({"g.png", png});
  writer.add(textured_square(0));
  writer.add_texture({"again.png", png});
  Object plain = textured_square(kNoTexture);
  plain.id = 1;
  writer.add(plain);
  writer.finish({});
  const SceneReader scene(dir.file("t.cwscene"));
  ASSERT_EQ(scene.texture_count(), 2u);
  EXPECT_EQ(scene.read_texture(0).encoded, png);
  EXPECT_EQ(scene.read_texture(1).name, "again.png");
  const Object back = scene.read_object(0);
  EXPECT_EQ(back.mesh.uvs, textured_square(0).mesh.uvs);
  EXPECT_EQ(back.mesh.texture, 0u);
  EXPECT_EQ(scene.read_object(1).mesh.texture, kNoTexture);
  EXPECT_EQ(scene.read_object(1).mesh.uvs.size(), 4u);

  build_world(dir.file("t.cwscene"), dir.file("t.cww"), BuildParams{});
  const World world(dir.file("t.cww"));
  ASSERT_EQ(world.texture_count(), 2u);
  EXPECT_EQ(world.read_texture(0), png);
  // The largest level within the asked side, each the previous halved, down to 1 × 1.
  for (const auto& [asked, w, h] : {std::tuple{100u, 16u, 8u}, {16u, 16u, 8u}, {15u, 8u, 4u}, {8u, 8u, 4u}, {3u, 2u, 1u}, {0u, 1u, 1u}}) {
    const Texture t = world.load_texture(1, asked);
    EXPECT_EQ(t.width, w) << "asked " << asked;
    EXPECT_EQ(t.height, h) << "asked " << asked;
  }
  // A level is the original halved by the box filter: the 8 × 4 level's texels are the means.
  const Texture level1 = world.load_texture(0, 8);
  const Texture halved = decode_texture(png, "g.png", 8);
  EXPECT_EQ(level1.texels, halved.texels) << "PNG levels are lossless";
  for (uint32_t level = 0; level < world.object(0).lod_count; ++level) {
    const Mesh m = world.decode_level(0, level, world.read_level(0, level));
    EXPECT_EQ(m.texture, 0u);
    EXPECT_EQ(m.uvs.size(), m.positions.size());
  }
  EXPECT_THROW(world.read_texture(2), Error);

  // One flipped byte inside the first texture's image: its record's checksum names it.
  std::vector<uint8_t> bytes = test::slurp(dir.file("t.cwscene"));
  const auto at = std::search(bytes.begin(), bytes.end(), png.begin(), png.end());
  ASSERT_NE(at, bytes.end());
  at[png.size() / 2] ^= 0x40;
  test::spit(dir.file("bad.cwscene"), bytes);
  const SceneReader bad(dir.file("bad.cwscene"));
  try {
    bad.read_texture(0);
    ADD_FAILURE() << "damage not found";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("texture 0: checksum mismatch"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cellwalk
