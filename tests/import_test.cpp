// Tests of the model importers and exporters (src/scene/*_reader.cpp, *_writer.cpp): real
// files from the CGAL and assimp test data against counts derived independently, round trips
// through OBJ and glTF, and the broken-file corpus in tests/data/broken.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <tuple>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#include <meshoptimizer.h>
#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using test::assimp_model;
using test::cgal_mesh;
using test::source_path;
using test::TempDir;

struct OffHeader {
  size_t vertices = 0, faces = 0;
};

// The counts an OFF file declares, read the simplest possible way (no comments before them).
OffHeader off_header(const std::string& path) {
  std::ifstream in(path);
  std::string keyword;
  OffHeader h;
  in >> keyword >> h.vertices >> h.faces;
  return h;
}

std::vector<uint8_t> bytes_of(const std::string& text) { return {text.begin(), text.end()}; }

Object parse_one(ModelFormat format, const std::string& text) {
  std::vector<Object> objects = parse_model(format, bytes_of(text), "test").objects;
  EXPECT_EQ(objects.size(), 1u);
  return objects.at(0);
}

// Parses and returns the error message, failing the test if there is none or another kind.
std::string parse_error(ModelFormat format, const std::string& text) {
  try {
    parse_model(format, bytes_of(text), "test").objects;
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no Error for:\n" << text;
  return {};
}

// --- OFF -----------------------------------------------------------------------------------

TEST(ImportOff, BunnyMatchesItsHeader) {
  const std::string path = cgal_mesh("bunny00.off");
  const OffHeader h = off_header(path);
  ASSERT_EQ(h.vertices, 37706u);  // what the file says, so a changed file is noticed
  std::vector<Object> objects = import_model(path, 5).objects;
  ASSERT_EQ(objects.size(), 1u);
  const Object& o = objects[0];
  EXPECT_EQ(o.id, 5u);
  EXPECT_EQ(o.name, "bunny00");
  EXPECT_EQ(o.mesh.vertex_count(), h.vertices);
  EXPECT_EQ(o.mesh.triangle_count(), h.faces);  // all triangles
  EXPECT_EQ(o.mesh.normals.size(), h.vertices);
  EXPECT_FALSE(o.bounds.empty());
  EXPECT_EQ(o.bounds.min, bounds_of(o.mesh).min);
}

TEST(ImportOff, ArmadilloMatchesItsHeader) {
  const std::string path = cgal_mesh("armadillo.off");
  const OffHeader h = off_header(path);
  std::vector<Object> objects = import_model(path).objects;
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].mesh.vertex_count(), h.vertices);
  EXPECT_EQ(objects[0].mesh.triangle_count(), h.faces);
}

TEST(ImportOff, ColouredOffWithComments) {
  std::vector<Object> objects = import_model(cgal_mesh("mesh_with_colors.off")).objects;
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].mesh.vertex_count(), 8u);
  EXPECT_EQ(objects[0].mesh.colors.size(), 8u);
  EXPECT_GT(objects[0].mesh.triangle_count(), 0u);
}

TEST(ImportOff, VariantsAndPolygons) {
  // A quad becomes a fan of two triangles; NOFF normals are kept; COFF colours in [0, 1].
  Object quad = parse_one(ModelFormat::kOff, "OFF 4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  EXPECT_EQ(quad.mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  Object noff = parse_one(ModelFormat::kOff,
                          "NOFF\n3 1\n0 0 0 0 0 -1\n1 0 0 0 0 -1\n0 1 0 0 0 -1\n3 0 1 2 255 0 0\n");
  EXPECT_EQ(noff.mesh.normals[0], Vec3(0, 0, -1));  // from the file, not recomputed
  Object coff = parse_one(ModelFormat::kOff,
                          "COFF\n3 1 0\n0 0 0 1.0 0.0 0.0 1.0\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n3 0 1 2\n");
  EXPECT_EQ(coff.mesh.colors[0], rgba8(255, 0, 0, 255));
}

// --- PLY -----------------------------------------------------------------------------------

TEST(ImportPly, CgalColouredTetraKeepsNormalsAndColours) {
  std::vector<Object> objects = import_model(cgal_mesh("colored_tetra.ply")).objects;
  ASSERT_EQ(objects.size(), 1u);
  const Mesh& m = objects[0].mesh;
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.triangle_count(), 4u);
  EXPECT_EQ(m.normals.size(), 4u);
  EXPECT_EQ(m.colors.size(), 4u);
}

TEST(ImportPly, CgalPointCloudHasVerticesAndNoTriangles) {
  std::vector<Object> objects = import_model(cgal_mesh("b9.ply")).objects;
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].mesh.vertex_count(), 22300u);  // "element vertex 22300"
  EXPECT_EQ(objects[0].mesh.triangle_count(), 0u);    // "element face 0"
}

TEST(ImportPly, AssimpAsciiAndBinaryCubesAgree) {
  // cube.ply: 8 vertices, 6 quads (uint8/int32 type names); cube_binary.ply: 12 triangles.
  const Object ascii = import_model(assimp_model("PLY/cube.ply")).objects.at(0);
  const Object binary = import_model(assimp_model("PLY/cube_binary.ply")).objects.at(0);
  EXPECT_EQ(ascii.mesh.vertex_count(), 8u);
  EXPECT_EQ(ascii.mesh.triangle_count(), 12u);
  EXPECT_EQ(binary.mesh.vertex_count(), 8u);
  EXPECT_EQ(binary.mesh.triangle_count(), 12u);
}

TEST(ImportPly, AssimpFilesWithExtraPropertiesAndFloatColours) {
  const Object wuson = import_model(assimp_model("PLY/Wuson.ply")).objects.at(0);
  EXPECT_EQ(wuson.mesh.vertex_count(), 11184u);  // s t skipped, free-text header line skipped
  EXPECT_EQ(wuson.mesh.triangle_count(), 3732u);
  const Object colored = import_model(assimp_model("PLY/float-color.ply")).objects.at(0);
  ASSERT_EQ(colored.mesh.colors.size(), 3u);
}

TEST(ImportPly, TruncatedBinaryNamesTheByteOffset) {
  // assimp's pond.0.ply declares 70051 vertices of 31 bytes but holds 69 bytes less.
  const std::string path = assimp_model("PLY/pond.0.ply");
  try {
    import_model(path).objects;
    FAIL() << "truncated file accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + "@"), std::string::npos) << e.what();
  }
}

std::string be32(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return {char(u >> 24), char(u >> 16), char(u >> 8), char(u)};
}

TEST(ImportPly, BigEndianMatchesAscii) {
  const std::string header =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar flags\nelement face 1\nproperty list ushort short vertex_index\n"
      "element extra 2\nproperty list uchar double stuff\nend_header\n";
  std::string be = "ply\nformat binary_big_endian 1.0\n" + header;
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0.5f};
  for (int i = 0; i < 3; ++i) be += be32(v[3 * i]) + be32(v[3 * i + 1]) + be32(v[3 * i + 2]) + '\x07';
  be += std::string("\0\x03\0\0\0\x01\0\x02", 8);  // face: ushort count 3, shorts 0 1 2
  be += std::string("\0\x01", 2) + std::string(8, '\0');  // extra: empty list, one double
  const std::string ascii = "ply\nformat ascii 1.0\n" + header +
                            "0 0 0 7\n1 0 0 7\n0 1 0.5 7\n3 0 1 2\n0\n1 0\n";
  const Object a = parse_one(ModelFormat::kPly, be);
  const Object b = parse_one(ModelFormat::kPly, ascii);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.indices, b.mesh.indices);
  EXPECT_EQ(a.mesh.positions[2], Vec3(0, 1, 0.5f));
}

// --- OBJ -----------------------------------------------------------------------------------

TEST(ImportObj, AssimpModels) {
  const Object box = import_model(assimp_model("OBJ/box.obj")).objects.at(0);
  EXPECT_EQ(box.mesh.vertex_count(), 8u);
  EXPECT_EQ(box.mesh.triangle_count(), 12u);  // 6 quads
  const Object colored = import_model(assimp_model("OBJ/cube_with_vertexcolors.obj")).objects.at(0);
  EXPECT_EQ(colored.mesh.colors.size(), 8u);
  EXPECT_EQ(colored.mesh.triangle_count(), 12u);
  size_t spider_triangles = 0;
  const std::vector<Object> spider = import_model(assimp_model("OBJ/spider.obj")).objects;  // many groups
  for (const Object& part : spider) spider_triangles += part.mesh.triangle_count();
  EXPECT_GT(spider_triangles, 1000u);
  EXPECT_GT(spider.size(), 10u);
}

TEST(ImportObj, ReferenceFormsAndNegativeIndices) {
  const Object o = parse_one(ModelFormat::kObj,
                             "mtllib x.mtl\no a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\n"
                             "vn 0 0 1\ng b\nusemtl m\nf 1/1 2/1/1 3//1 4\nf -4 -3 -2\n");
  EXPECT_EQ(o.mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 1, 2}));
}

// --- glTF ----------------------------------------------------------------------------------

struct GltfCounts {
  size_t objects = 0, triangles = 0;
};

// An oracle independent of tinygltf: reads the GLB's JSON chunk and counts, over the mesh nodes
// of the default scene, the triangle-list primitives with triangles and their index counts.
GltfCounts glb_oracle(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> b((std::istreambuf_iterator<char>(in)), {});
  uint32_t json_length;
  std::memcpy(&json_length, b.data() + 12, 4);
  const auto doc = nlohmann::json::parse(b.begin() + 20, b.begin() + 20 + json_length);
  GltfCounts c;
  std::vector<int> stack = doc["scenes"][doc.value("scene", 0)]["nodes"].get<std::vector<int>>();
  while (!stack.empty()) {
    const auto& node = doc["nodes"][stack.back()];
    stack.pop_back();
    for (int child : node.value("children", std::vector<int>{})) stack.push_back(child);
    if (!node.contains("mesh")) continue;
    for (const auto& p : doc["meshes"][node["mesh"].get<int>()]["primitives"]) {
      if (p.value("mode", 4) != 4) continue;
      const size_t triangles = doc["accessors"][p["indices"].get<int>()]["count"].get<size_t>() / 3;
      c.objects += triangles > 0;
      c.triangles += triangles;
    }
  }
  return c;
}

TEST(ImportGltf, CylinderEngineGivesOneObjectPerPrimitive) {
  const std::string path = assimp_model("glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
  const GltfCounts expected = glb_oracle(path);
  std::vector<Object> objects = import_model(path, 100).objects;
  ASSERT_GT(objects.size(), 10u);
  EXPECT_EQ(objects.size(), expected.objects);
  size_t triangles = 0;
  for (size_t i = 0; i < objects.size(); ++i) {
    EXPECT_EQ(objects[i].id, 100 + i);
    EXPECT_FALSE(objects[i].name.empty());
    EXPECT_FALSE(objects[i].bounds.empty());
    triangles += objects[i].mesh.triangle_count();
  }
  EXPECT_EQ(triangles, expected.triangles);
  EXPECT_GT(triangles, 10000u);
}

TEST(ImportGltf, ExternalBinIsReadFromFilesNotFromMemory) {
  const std::string path = assimp_model("glTF2/BoxTextured-glTF/BoxTextured.gltf");
  std::vector<Object> objects = import_model(path).objects;
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].mesh.triangle_count(), 12u);
  // The same JSON from memory must not reach for BoxTextured0.bin on disk.
  std::ifstream in(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_FALSE(parse_error(ModelFormat::kGltf, text).empty());
}

TEST(ImportGltf, AssimpBrokenSamplesGiveErrors) {
  for (const char* name : {"glTF2/IndexOutOfRange/IndexOutOfRange.gltf",
                           "glTF2/RecursiveNodes/RecursiveNodes.gltf",
                           "glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
                           "glTF2/MissingBin/BoxTextured.gltf"}) {
    const std::string path = assimp_model(name);
    EXPECT_THROW(import_model(path).objects, Error) << path;
  }
}

// --- exporters -----------------------------------------------------------------------------

void expect_same_geometry(const Object& a, const Object& b) {
  ASSERT_EQ(a.mesh.vertex_count(), b.mesh.vertex_count());
  ASSERT_EQ(a.mesh.triangle_count(), b.mesh.triangle_count());
  EXPECT_EQ(a.mesh.indices, b.mesh.indices);
  for (size_t i = 0; i < a.mesh.positions.size(); ++i)
    ASSERT_LT(glm::length(a.mesh.positions[i] - b.mesh.positions[i]), 1e-5f) << "vertex " << i;
}

TEST(Export, BunnyRoundTripsThroughObjGltfAndGlb) {
  const Object bunny = import_model(cgal_mesh("bunny00.off")).objects.at(0);
  TempDir dir;
  for (const char* name : {"bunny.obj", "bunny.gltf", "bunny.glb"}) {
    const std::string path = dir.file(name);
    if (format_of(path) == ModelFormat::kObj) {
      ObjWriter w(path);
      w.add(bunny);
      w.finish();
    } else {
      GltfWriter w(path);
      w.add(bunny);
      w.finish();
    }
    std::vector<Object> back = import_model(path).objects;
    ASSERT_EQ(back.size(), 1u) << name;
    expect_same_geometry(bunny, back[0]);
    // OBJ keeps the "o" name, glTF the node name.
    EXPECT_EQ(back[0].name, "bunny00") << name;
  }
  EXPECT_TRUE(std::filesystem::exists(dir.file("bunny.bin")));
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().find(".cwtmp."), std::string::npos) << entry.path();
}

TEST(Export, SeveralObjectsKeepColoursAndOrder) {
  Object a = parse_one(ModelFormat::kOff, "COFF 3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2\n");
  a.name = "a";
  a.color = rgba8(10, 20, 30, 255);
  Object b = parse_one(ModelFormat::kOff, "OFF 4 1 0\n0 0 5\n1 0 5\n1 1 5\n0 1 5\n4 0 1 2 3\n");
  b.name = "b";
  TempDir dir;
  GltfWriter w(dir.file("two.glb"));
  w.add(a);
  w.add(b);
  w.finish();
  std::vector<Object> back = import_model(dir.file("two.glb")).objects;
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].name, "a");
  EXPECT_EQ(back[0].color, a.color);
  EXPECT_EQ(back[0].mesh.colors, a.mesh.colors);
  expect_same_geometry(b, back[1]);
}

TEST(Export, UnfinishedWriterLeavesNoFile) {
  TempDir dir;
  {
    ObjWriter w(dir.file("x.obj"));
    w.add(parse_one(ModelFormat::kOff, "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

// --- errors --------------------------------------------------------------------------------

TEST(ImportErrors, FormatAndFileProblems) {
  EXPECT_EQ(format_of("a/B.GLB"), ModelFormat::kGltf);
  EXPECT_EQ(format_of("x.Obj"), ModelFormat::kObj);
  EXPECT_THROW(format_of("x.stl"), Error);
  TempDir dir;
  std::filesystem::create_directory(dir.file("d.obj"));
  for (const std::string& path : {dir.file("d.obj"), dir.file("missing.off")}) {
    try {
      import_model(path).objects;
      ADD_FAILURE() << path;
    } catch (const Error& e) {
      EXPECT_TRUE(std::string(e.what()).starts_with(path + ": ")) << e.what();
    }
  }
}

TEST(ImportErrors, TextErrorsNameTheLine) {
  EXPECT_EQ(parse_error(ModelFormat::kOff, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n"),
            "test:6: face uses vertex 9 but there are 3 vertices");
  EXPECT_EQ(parse_error(ModelFormat::kObj, "v 0 0 0\n\nf 1 2 3\n"),
            "test:3: face uses vertex 2 but 1 vertices are defined so far");
}

// --- bad model data (issue 13, items 6 and 9) -------------------------------------------------

// A GLB of one triangle: positions, normals and indices in one binary chunk, accessors 0, 1
// and 2; `index_type` is the index accessor's component type, `node` the one node.
// A GLB of a JSON document and its binary chunk (both padded to 4 bytes).
std::vector<uint8_t> glb_of(const nlohmann::json& doc, std::string bin) {
  std::string json = doc.dump();
  json.append((4 - json.size() % 4) % 4, ' ');
  bin.append((4 - bin.size() % 4) % 4, '\0');
  std::string glb(12, '\0');
  const auto chunk = [&glb](const std::string& data, uint32_t type) {
    const uint32_t length = uint32_t(data.size());
    glb.append(reinterpret_cast<const char*>(&length), 4).append(reinterpret_cast<const char*>(&type), 4).append(data);
  };
  chunk(json, 0x4E4F534Au);
  chunk(bin, 0x004E4942u);
  const uint32_t header[3] = {0x46546C67u, 2, uint32_t(glb.size())};
  std::memcpy(glb.data(), header, 12);
  return bytes_of(glb);
}

// `patch` is merged into the document last (RFC 7386: an array given replaces the whole array).
std::vector<uint8_t> triangle_glb(const std::array<float, 9>& normals, int index_type,
                                  const nlohmann::json& node = {{"mesh", 0}},
                                  const nlohmann::json& patch = nlohmann::json::object()) {
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::string bin(reinterpret_cast<const char*>(positions), 36);
  bin.append(reinterpret_cast<const char*>(normals.data()), 36);
  // Three indices of the type, padded to 4 bytes; the float ones are 0, 1.7, 2 (1.7 once became
  // vertex 1).
  const auto append = [&bin](const auto& values) { bin.append(reinterpret_cast<const char*>(&values), sizeof values); };
  if (index_type == 5126) append(std::array<float, 3>{0.0f, 1.7f, 2.0f});
  else if (index_type >= 5124) append(std::array<int32_t, 3>{0, 1, 2});
  else if (index_type >= 5122) append(std::array<int16_t, 4>{0, 1, 2, 0});
  else append(std::array<int8_t, 4>{0, 1, 2, 0});
  nlohmann::json doc = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {node}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}, {"indices", 2}}}}}}},
      {"buffers", {{{"byteLength", bin.size()}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 72}, {"byteLength", bin.size() - 72}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 2}, {"componentType", index_type}, {"count", 3}, {"type", "SCALAR"}}}}};
  doc.merge_patch(patch);
  return glb_of(doc, bin);
}

std::string gltf_error(const std::vector<uint8_t>& glb) {
  try {
    parse_model(ModelFormat::kGltf, glb, "test.glb").objects;
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no Error";
  return {};
}

// A PLY triangle with normals; `body` formats one vertex's x y z nx ny nz.
std::string ply_header(const char* format) {
  return std::string("ply\nformat ") + format +
         " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
         "property float nx\nproperty float ny\nproperty float nz\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
}

std::string binary_ply_with_normal(float bad) {
  std::string ply = ply_header("binary_little_endian");
  const float v[18] = {0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, bad, 1};
  ply.append(reinterpret_cast<const char*>(v), sizeof v);
  const int32_t face[3] = {0, 1, 2};
  ply += '\x03';
  ply.append(reinterpret_cast<const char*>(face), sizeof face);
  return ply;
}

TEST(ImportErrors, NonFiniteNormalsAreRefusedNamingTheVertex) {
  const std::string ascii_ply = ply_header("ascii") + "0 0 0 0 0 1\n1 0 0 nan 0 1\n0 1 0 0 0 1\n3 0 1 2\n";
  const std::string noff = "NOFF\n3 1\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 -inf 1\n3 0 1 2\n";
  EXPECT_EQ(parse_error(ModelFormat::kPly, ascii_ply).rfind("test: vertex 1 has a non-finite normal", 0), 0u);
  EXPECT_EQ(parse_error(ModelFormat::kOff, noff).rfind("test: vertex 2 has a non-finite normal", 0), 0u);
  for (const float bad : {std::nanf(""), float(INFINITY)}) {
    EXPECT_EQ(parse_error(ModelFormat::kPly, binary_ply_with_normal(bad)).rfind("test: vertex 2 has a non-finite normal", 0), 0u);
    const std::string glb = gltf_error(triangle_glb({0, 0, 1, bad, 0, 1, 0, 0, 1}, 5123));
    EXPECT_EQ(glb.rfind("test.glb: node 0: vertex 1 has a non-finite normal", 0), 0u) << glb;
  }
  // The same files with finite normals read, and keep them.
  EXPECT_EQ(parse_one(ModelFormat::kPly, binary_ply_with_normal(0.0f)).mesh.normals[2], Vec3(0, 0, 1));
  const auto good = parse_model(ModelFormat::kGltf, triangle_glb({0, 0, 1, 0, 0, 1, 0, 0, 1}, 5123), "test.glb").objects;
  ASSERT_EQ(good.size(), 1u);
  EXPECT_EQ(good[0].mesh.normals[1], Vec3(0, 0, 1));
}

// glTF indices are unsigned integers; a float accessor once truncated 1.7 to vertex 1.
TEST(ImportErrors, GltfIndicesOfAFloatTypeAreRefused) {
  const std::string message = gltf_error(triangle_glb({0, 0, 1, 0, 0, 1, 0, 0, 1}, 5126));
  EXPECT_EQ(message.rfind("test.glb: node 0 mesh 0 primitive 0: index accessor 2 has component type 5126", 0), 0u)
      << message;
  // Signed types are not indices either; the unsigned ones read.
  for (int signed_type : {5120, 5122, 5124})
    EXPECT_NE(gltf_error(triangle_glb({0, 0, 1, 0, 0, 1, 0, 0, 1}, signed_type)).find("has component type " + std::to_string(signed_type)),
              std::string::npos);
  for (int unsigned_type : {5121, 5123, 5125})
    EXPECT_EQ(parse_model(ModelFormat::kGltf, triangle_glb({0, 0, 1, 0, 0, 1, 0, 0, 1}, unsigned_type), "test.glb").objects
                  .at(0).mesh.indices,
              (std::vector<uint32_t>{0, 1, 2}));
}

// A node scaled to zero (how some exporters hide one) has no normal matrix; its normals are
// recomputed rather than turned into NaN, so the file still imports. A node that scales the
// triangle past the coordinate bound is refused like a vertex written there.
// An image whose buffer view runs past its buffer: tinygltf hands such a view over unchecked, so
// cellwalk reads a view's image bytes only after checking its bounds. The mesh imports
// untextured and nothing past the buffer is read (the ASan build checks that).
TEST(ImportGltf, ImageViewPastItsBufferLeavesTheMeshUntextured) {
  const nlohmann::json patch = {
      {"meshes",
       {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 3}}}, {"indices", 2}, {"material", 0}}}}}}},
      {"materials", {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}}},
      {"textures", {{{"source", 0}}}},
      {"images", {{{"bufferView", 3}, {"mimeType", "image/png"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 72}, {"byteLength", 12}},
        {{"buffer", 0}, {"byteOffset", 8}, {"byteLength", 1 << 20}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 2}, {"componentType", 5125}, {"count", 3}, {"type", "SCALAR"}},
        {{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}}}}};
  try {
    const ImportedModel model = parse_model(ModelFormat::kGltf, triangle_glb({0, 0, 1, 0, 0, 1, 0, 0, 1}, 5125, {{"mesh", 0}}, patch), "view.glb");
    EXPECT_TRUE(model.textures.empty());
    ASSERT_EQ(model.objects.size(), 1u);
    EXPECT_EQ(model.objects[0].mesh.texture, kNoTexture);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("view.glb"), std::string::npos) << e.what();
  }
}

TEST(ImportGltf, NodeTransformsKeepNormalsFiniteAndPositionsBounded) {
  const std::array<float, 9> up = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  const auto hidden = parse_model(ModelFormat::kGltf, triangle_glb(up, 5123, {{"mesh", 0}, {"scale", {0, 0, 0}}}), "test.glb").objects;
  ASSERT_EQ(hidden.size(), 1u);
  for (const Vec3& n : hidden[0].mesh.normals) EXPECT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z));
  const std::string message = gltf_error(triangle_glb(up, 5123, {{"mesh", 0}, {"scale", {1e8, 1, 1}}}));
  EXPECT_EQ(message.rfind("test.glb: node 0: vertex 1 (1e+08, 0, 0) has a coordinate beyond 1e7 m", 0), 0u) << message;
}

TEST(ImportErrors, CoordinatesBeyondTheBoundAreRefusedNamingTheVertex) {
  const std::string obj = "v 0 0 0\nv 3e38 0 0\nv 0 1 0\nf 1 2 3\n";
  EXPECT_EQ(parse_error(ModelFormat::kObj, obj),
            "test: vertex 1 (3e+38, 0, 0) has a coordinate beyond 1e7 m, the largest cellwalk handles; rescale the "
            "model (e.g. to metres) or move it nearer the origin");
  EXPECT_NE(parse_error(ModelFormat::kOff, "OFF 3 1 0\n0 0 0\n0 -1.5e7 0\n0 1 0\n3 0 1 2\n").find("vertex 1"),
            std::string::npos);
  EXPECT_NE(parse_error(ModelFormat::kPly, ply_header("ascii") + "0 0 0 0 0 1\n1 0 0 0 0 1\n0 0 2e7 0 0 1\n3 0 1 2\n")
                .find("vertex 2 (0, 0, 2e+07) has a coordinate beyond 1e7 m"),
            std::string::npos);
  // At the bound itself a model reads.
  EXPECT_EQ(parse_one(ModelFormat::kObj, "v 0 0 0\nv 1e7 0 0\nv 0 -1e7 0\nf 1 2 3\n").mesh.positions[2], Vec3(0, -1e7f, 0));
}

// Every file in the corpus must give an Error (not another exception, not a crash) whose
// message is one line and names the file.
TEST(ImportErrors, EveryBrokenFileGivesAnErrorNamingIt) {
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(source_path("tests/data/broken"))) {
    const std::string path = entry.path().string();
    ++files;
    try {
      import_model(path).objects;
      ADD_FAILURE() << path << " was accepted";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_TRUE(message.starts_with(path)) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    } catch (const std::exception& e) {
      ADD_FAILURE() << path << ": not a cellwalk::Error: " << e.what();
    }
  }
  EXPECT_GE(files, 50u);
}

// --- objects: OBJ groups, glTF primitives, patches -------------------------------------------

// Issue 16: an OBJ with 71 groups imported as 1 object. Each group is an object now, a group
// named again takes more faces, and "o A" + "g b" names the group "A/b".
TEST(ImportObj, EveryGroupIsAnObject) {
  std::string text;
  for (int g = 0; g < 71; ++g) {
    text += "g part" + std::to_string(g) + "\n";
    text += "v " + std::to_string(g) + " 0 0\nv " + std::to_string(g) + " 1 0\nv " + std::to_string(g) + " 0 1\nf -3 -2 -1\n";
  }
  text += "g part3\nf 1 2 3\ng\no Named\ng sub\nf 4 5 6\n";
  const std::vector<Object> objects = parse_model(ModelFormat::kObj, bytes_of(text), "groups.obj", 7).objects;
  ASSERT_EQ(objects.size(), 72u);
  for (int g = 0; g < 71; ++g) {
    EXPECT_EQ(objects[g].name, "part" + std::to_string(g));
    EXPECT_EQ(objects[g].id, 7u + g);
    EXPECT_EQ(objects[g].mesh.triangle_count(), g == 3 ? 2u : 1u);
    EXPECT_EQ(objects[g].bounds.min.x, g == 3 ? 0.0f : float(g));
  }
  EXPECT_EQ(objects[71].name, "Named/sub");
  EXPECT_EQ(objects[71].mesh.positions.front(), Vec3(1, 0, 0));
  // No group at all: one object named after the file.
  EXPECT_EQ(parse_model(ModelFormat::kObj, bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "dir/plain.obj").objects.at(0).name, "plain");
}

// Materials: an object's colour is its material's Kd; an object of several materials gets
// each vertex its material's colour (a vertex shared by two materials is split).
TEST(ImportObj, MaterialColoursFromTheMtlFileBesideIt) {
  TempDir dir;
  std::ofstream(dir.file("m.mtl")) << "newmtl red\nKd 1 0 0\n# blue\nnewmtl blue one\nKd 0 0 1.0\n";
  std::ofstream(dir.file("m.obj")) << "mtllib m.mtl missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                                      "g a\nusemtl red\nf 1 2 3\ng b\nf 2 4 3\nusemtl blue one\nf 1 2 3\n";
  const std::vector<Object> objects = import_model(dir.file("m.obj")).objects;
  ASSERT_EQ(objects.size(), 2u);
  EXPECT_EQ(objects[0].color, rgba8(255, 0, 0));
  EXPECT_TRUE(objects[0].mesh.colors.empty());
  EXPECT_EQ(objects[1].color, rgba8(255, 0, 0));
  ASSERT_EQ(objects[1].mesh.colors.size(), 6u);  // vertices 2 and 3 in both materials
  EXPECT_EQ(objects[1].mesh.colors[objects[1].mesh.indices[0]], rgba8(255, 0, 0));
  EXPECT_EQ(objects[1].mesh.colors[objects[1].mesh.indices[3]], rgba8(0, 0, 255));
  // From memory, nothing beside it is read: the default colour.
  EXPECT_EQ(parse_model(ModelFormat::kObj, test::slurp(dir.file("m.obj")), "m.obj").objects.at(0).color, Object{}.color);
  // A real file: the spider's 19 groups, its body in HLeibTex (Kd 0.690196 0.639216 0.615686).
  const std::vector<Object> spider = import_model(assimp_model("OBJ/spider.obj")).objects;
  ASSERT_EQ(spider.size(), 19u);
  const auto body = std::find_if(spider.begin(), spider.end(), [](const Object& o) { return o.name == "HLeib01"; });
  ASSERT_NE(body, spider.end());
  EXPECT_EQ(body->color, rgba8(176, 163, 157));
}

// One object per triangle primitive, each with its node's transform and its material's colour.
TEST(ImportGltf, EachPrimitiveIsAnObjectWithItsTransformAndColour) {
  const nlohmann::json patch = {
      {"scenes", {{{"nodes", {0, 1}}}}},
      {"nodes", {{{"mesh", 0}, {"translation", {10, 0, 0}}}, {{"mesh", 0}, {"name", "lifted"}, {"translation", {0, 5, 0}}}}},
      {"materials", {{{"pbrMetallicRoughness", {{"baseColorFactor", {1, 0, 0, 1}}}}}, {{"pbrMetallicRoughness", {{"baseColorFactor", {0, 1, 0, 1}}}}}}},
      {"meshes",
       {{{"primitives",
          {{{"attributes", {{"POSITION", 0}}}, {"indices", 2}, {"material", 0}},
           {{"attributes", {{"POSITION", 0}}}, {"indices", 2}, {"material", 1}},
           {{"attributes", {{"POSITION", 0}}}, {"indices", 2}, {"mode", 1}}}}}}}};  // lines: skipped
  const std::vector<Object> objects =
      parse_model(ModelFormat::kGltf, triangle_glb({0, 0, 1, 0, 0, 1, 0, 0, 1}, 5123, {}, patch), "two.glb").objects;
  ASSERT_EQ(objects.size(), 4u);
  EXPECT_EQ(objects[0].color, rgba8(255, 0, 0));
  EXPECT_EQ(objects[1].color, rgba8(0, 255, 0));
  EXPECT_EQ(objects[0].bounds.min, Vec3(10, 0, 0));
  EXPECT_EQ(objects[3].bounds.min, Vec3(0, 5, 0));
  EXPECT_EQ(objects[2].name, "lifted/0");
  EXPECT_EQ(objects[3].name, "lifted/1");
}

// Compressed glTF once failed with "Invalid `byteLength'" or "accessor[0] invalid bufferView".
TEST(ImportGltf, RequiredExtensionsNotReadAreNamed) {
  const std::array<float, 9> up = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  for (const char* ext : {"EXT_texture_webp", "EXT_future_thing"}) {
    const std::string message = gltf_error(triangle_glb(up, 5123, {{"mesh", 0}}, {{"extensionsUsed", {ext}}, {"extensionsRequired", {ext}}}));
    EXPECT_EQ(message.rfind(std::string("test.glb: requires the glTF extension ") + ext + ", which cellwalk cannot read yet; ", 0), 0u) << message;
  }
  // Quantized attributes are read; an extension only used, not required, is ignored.
  EXPECT_EQ(parse_model(ModelFormat::kGltf,
                        triangle_glb(up, 5123, {{"mesh", 0}}, {{"extensionsUsed", {"KHR_mesh_quantization", "EXT_x"}}, {"extensionsRequired", {"KHR_mesh_quantization"}}}),
                        "q.glb").objects.size(), 1u);
}

// A GLB of `mesh` as gltfpack -cc writes it: positions through the exponential filter (15-bit
// mantissa), normals octahedral in 4 bytes, indices as a compressed triangle list, each view
// compressed into buffer 0 with a fallback buffer 1 that holds no data.
std::vector<uint8_t> meshopt_glb(const Mesh& mesh, const char* extension) {
  const size_t n = mesh.positions.size();
  std::vector<uint32_t> exp_positions(n * 3);
  meshopt_encodeFilterExp(exp_positions.data(), n, 12, 15, &mesh.positions[0].x);
  std::vector<float> xyzw;
  for (const Vec3& v : mesh.normals) xyzw.insert(xyzw.end(), {v.x, v.y, v.z, 0.0f});
  std::vector<int8_t> oct_normals(n * 4);
  meshopt_encodeFilterOct(oct_normals.data(), n, 4, 8, xyzw.data());
  std::string bin;
  nlohmann::json views = nlohmann::json::array();
  size_t fallback_at = 0;
  const auto add = [&](std::vector<uint8_t> packed, size_t stride, size_t count, const char* mode, const char* filter) {
    nlohmann::json view = {{"buffer", 1}, {"byteOffset", fallback_at}, {"byteLength", stride * count}};
    if (std::string(mode) == "ATTRIBUTES") view["byteStride"] = stride;
    view["extensions"][extension] = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", packed.size()},
                                     {"byteStride", stride}, {"count", count}, {"mode", mode}, {"filter", filter}};
    bin.append(reinterpret_cast<const char*>(packed.data()), packed.size());
    bin.append((4 - bin.size() % 4) % 4, '\0');
    fallback_at += (stride * count + 3) / 4 * 4;
    views.push_back(view);
  };
  const auto vertices = [](const void* data, size_t count, size_t stride) {
    std::vector<uint8_t> out(meshopt_encodeVertexBufferBound(count, stride));
    out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), data, count, stride));
    return out;
  };
  add(vertices(exp_positions.data(), n, 12), 12, n, "ATTRIBUTES", "EXPONENTIAL");
  add(vertices(oct_normals.data(), n, 4), 4, n, "ATTRIBUTES", "OCTAHEDRAL");
  std::vector<uint8_t> indices(meshopt_encodeIndexBufferBound(mesh.indices.size(), n));
  indices.resize(meshopt_encodeIndexBuffer(indices.data(), indices.size(), mesh.indices.data(), mesh.indices.size()));
  add(indices, 4, mesh.indices.size(), "TRIANGLES", "NONE");
  const nlohmann::json doc = {
      {"asset", {{"version", "2.0"}}},
      {"extensionsUsed", {extension}},
      {"extensionsRequired", {extension}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}, {"indices", 2}}}}}}},
      {"buffers", {{{"byteLength", bin.size()}}, {{"byteLength", fallback_at}, {"extensions", {{extension, {{"fallback", true}}}}}}}},
      {"bufferViews", views},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", n}, {"type", "VEC3"}},
        {{"bufferView", 1}, {"componentType", 5120}, {"normalized", true}, {"count", n}, {"type", "VEC3"}},
        {{"bufferView", 2}, {"componentType", 5125}, {"count", mesh.indices.size()}, {"type", "SCALAR"}}}}};
  return glb_of(doc, bin);
}

// Issue 16: gltfpack -cc output failed with "Invalid `byteLength'". Decoded with meshoptimizer,
// it gives the cow's geometry: the same triangles, positions within the 15-bit mantissa's
// rounding, normals within the 8-bit octahedral encoding's.
TEST(ImportGltf, MeshoptCompressedViewsDecodeToTheSameGeometry) {
  const Object cow = import_model(cgal_mesh("cow.off")).objects.at(0);
  for (const char* extension : {"EXT_meshopt_compression", "KHR_meshopt_compression"}) {
    const std::vector<uint8_t> glb = meshopt_glb(cow.mesh, extension);
    const std::vector<Object> back = parse_model(ModelFormat::kGltf, glb, "cow.glb").objects;
    ASSERT_EQ(back.size(), 1u) << extension;
    const Mesh& m = back[0].mesh;
    // The index codec may rotate a triangle's corners (its winding kept): compare rotated to the
    // smallest corner first.
    const auto rotated = [](std::vector<uint32_t> v) {
      for (size_t t = 0; t + 2 < v.size(); t += 3)
        while (v[t] > v[t + 1] || v[t] > v[t + 2]) std::rotate(v.begin() + t, v.begin() + t + 1, v.begin() + t + 3);
      return v;
    };
    EXPECT_EQ(rotated(m.indices), rotated(cow.mesh.indices));
    ASSERT_EQ(m.positions.size(), cow.mesh.positions.size());
    float worst = 0, worst_normal = 0;
    for (size_t i = 0; i < m.positions.size(); ++i) {
      worst = std::max(worst, glm::length(m.positions[i] - cow.mesh.positions[i]) / std::max(glm::length(cow.mesh.positions[i]), 1e-3f));
      worst_normal = std::max(worst_normal, glm::length(m.normals[i] - cow.mesh.normals[i]));
    }
    EXPECT_LT(worst, 1e-4f) << extension;
    EXPECT_LT(worst_normal, 0.03f) << extension;
    EXPECT_GT(worst + worst_normal, 0.0f) << "quantised, so not bit-exact: the compressed views were read";
    // Damaged compressed data is one error naming the view, not a crash or a wrong mesh.
    std::vector<uint8_t> damaged = glb;
    const size_t bin_at = 20 + size_t(damaged[12] | damaged[13] << 8 | damaged[14] << 16) + 8;
    std::fill(damaged.begin() + bin_at, damaged.begin() + bin_at + 64, uint8_t(0xFF));
    const std::string message = parse_error(ModelFormat::kGltf, std::string(damaged.begin(), damaged.end()));
    EXPECT_NE(message.find("bufferView 0"), std::string::npos) << message;
  }
}

// A GLB of `mesh` as Draco-compressing exporters write it: one primitive whose POSITION, NORMAL
// and index accessors have no buffer view, and its KHR_draco_mesh_compression stream (the
// edgebreaker codec, positions at 14 bits, normals at 10) in buffer view 0.
std::vector<uint8_t> draco_glb(const Mesh& mesh) {
  draco::Mesh dm;
  const size_t n = mesh.positions.size();
  dm.set_num_points(uint32_t(n));
  const auto add = [&dm, n](draco::GeometryAttribute::Type type, const std::vector<Vec3>& values) {
    draco::GeometryAttribute attribute;
    attribute.Init(type, nullptr, 3, draco::DT_FLOAT32, false, 12, 0);
    draco::PointAttribute* a = dm.attribute(dm.AddAttribute(attribute, true, uint32_t(n)));
    for (size_t i = 0; i < n; ++i) a->SetAttributeValue(draco::AttributeValueIndex(uint32_t(i)), &values[i].x);
    return a->unique_id();
  };
  const uint32_t position_id = add(draco::GeometryAttribute::POSITION, mesh.positions);
  const uint32_t normal_id = add(draco::GeometryAttribute::NORMAL, mesh.normals);
  for (size_t t = 0; t < mesh.triangle_count(); ++t)
    dm.AddFace({draco::PointIndex(mesh.indices[3 * t]), draco::PointIndex(mesh.indices[3 * t + 1]), draco::PointIndex(mesh.indices[3 * t + 2])});
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 14);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, 10);
  encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
  draco::EncoderBuffer stream;
  const draco::Status status = encoder.EncodeMeshToBuffer(dm, &stream);
  EXPECT_TRUE(status.ok()) << status.error_msg();
  const std::string bin(stream.data(), stream.size());
  const char* ext = "KHR_draco_mesh_compression";
  const nlohmann::json doc = {
      {"asset", {{"version", "2.0"}}},
      {"extensionsUsed", {ext}},
      {"extensionsRequired", {ext}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}, {"indices", 2},
                                    {"extensions", {{ext, {{"bufferView", 0}, {"attributes", {{"POSITION", position_id}, {"NORMAL", normal_id}}}}}}}}}}}}},
      {"buffers", {{{"byteLength", bin.size()}}}},
      {"bufferViews", {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", bin.size()}}}},
      {"accessors",
       {{{"componentType", 5126}, {"count", n}, {"type", "VEC3"}},
        {{"componentType", 5126}, {"count", n}, {"type", "VEC3"}},
        {{"componentType", 5125}, {"count", mesh.indices.size()}, {"type", "SCALAR"}}}}};
  return glb_of(doc, bin);
}

// Issue 16: a Draco file failed with "accessor[0] invalid bufferView". Decoded with libdraco it
// gives the cow: Draco renumbers vertices and corners, so each decoded vertex is matched to the
// nearest original one (brute force) within the 14-bit quantisation, and the triangles, as
// matched vertex triples, are the original ones; normals within the 10-bit quantisation.
TEST(ImportGltf, DracoCompressedPrimitivesDecodeToTheSameGeometry) {
  const Object cow = import_model(cgal_mesh("cow.off")).objects.at(0);
  const Mesh& original = cow.mesh;
  const std::vector<uint8_t> glb = draco_glb(original);
  const std::vector<Object> back = parse_model(ModelFormat::kGltf, glb, "cow.glb").objects;
  ASSERT_EQ(back.size(), 1u);
  const Mesh& m = back[0].mesh;
  const Vec3 extent = cow.bounds.max - cow.bounds.min;
  const float tolerance = std::max({extent.x, extent.y, extent.z}) / (1 << 14);
  // The first original vertex at each position stands for all of them.
  const auto first_at = [&original](const Vec3& p) {
    size_t best = 0;
    for (size_t j = 1; j < original.positions.size(); ++j)
      if (glm::length(original.positions[j] - p) < glm::length(original.positions[best] - p)) best = j;
    return best;
  };
  std::vector<size_t> match(m.positions.size());
  float worst = 0, worst_normal = 0;
  for (size_t i = 0; i < m.positions.size(); ++i) {
    match[i] = first_at(m.positions[i]);
    worst = std::max(worst, glm::length(m.positions[i] - original.positions[match[i]]));
    // The cow has two vertices at one place, with different normals: either may be the one.
    float nearest_normal = 2;
    for (size_t j = 0; j < original.positions.size(); ++j)
      if (glm::length(original.positions[j] - original.positions[match[i]]) == 0)
        nearest_normal = std::min(nearest_normal, glm::length(m.normals[i] - original.normals[j]));
    worst_normal = std::max(worst_normal, nearest_normal);
  }
  EXPECT_LT(worst, tolerance);
  EXPECT_GT(worst, 0.0f) << "quantised, so not bit-exact: the Draco stream was read";
  EXPECT_LT(worst_normal, 0.02f);
  const auto triangles = [](const std::vector<uint32_t>& indices, const auto& canonical) {
    std::vector<std::array<size_t, 3>> out;
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
      std::array<size_t, 3> c = {canonical(indices[t]), canonical(indices[t + 1]), canonical(indices[t + 2])};
      while (c[0] > c[1] || c[0] > c[2]) std::rotate(c.begin(), c.begin() + 1, c.end());
      out.push_back(c);
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  EXPECT_EQ(triangles(m.indices, [&match](uint32_t i) { return match[i]; }),
            triangles(original.indices, [&](uint32_t i) { return first_at(original.positions[i]); }));

  // A damaged stream, or an attribute id the stream does not have, is one error naming the primitive.
  std::vector<uint8_t> damaged = glb;
  const size_t bin_at = 20 + size_t(damaged[12] | damaged[13] << 8 | damaged[14] << 16) + 8;
  std::fill(damaged.begin() + bin_at + 8, damaged.begin() + bin_at + 200, uint8_t(0xA5));
  std::string message = parse_error(ModelFormat::kGltf, std::string(damaged.begin(), damaged.end()));
  EXPECT_NE(message.find("mesh 0 primitive 0"), std::string::npos) << message;
  nlohmann::json doc = nlohmann::json::parse(std::string(glb.begin() + 20, glb.begin() + bin_at - 8));
  doc["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["attributes"]["NORMAL"] = 77;
  const std::vector<uint8_t> renamed = glb_of(doc, std::string(glb.begin() + bin_at, glb.end()));
  message = parse_error(ModelFormat::kGltf, std::string(renamed.begin(), renamed.end()));
  EXPECT_NE(message.find("names Draco attribute 77, which the stream does not have"), std::string::npos) << message;

  // Found in review. A strip compressed with Draco decodes to a list: read as one, not as a strip.
  nlohmann::json strip = nlohmann::json::parse(std::string(glb.begin() + 20, glb.begin() + bin_at - 8));
  strip["meshes"][0]["primitives"][0]["mode"] = 5;
  const std::vector<uint8_t> strip_glb = glb_of(strip, std::string(glb.begin() + bin_at, glb.end()));
  EXPECT_EQ(parse_model(ModelFormat::kGltf, strip_glb, "strip.glb").objects.at(0).mesh.triangle_count(), original.triangle_count());
  // Fields of the wrong JSON type are one error naming the file, not a library's exception.
  for (const auto& [pointer, value] : {std::pair<const char*, nlohmann::json>{"/accessors/0/type", 5},
                                       {"/accessors", "none"},
                                       {"/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression/attributes", 3}}) {
    nlohmann::json bad = nlohmann::json::parse(std::string(glb.begin() + 20, glb.begin() + bin_at - 8));
    bad[nlohmann::json::json_pointer(pointer)] = value;
    const std::vector<uint8_t> bad_glb = glb_of(bad, std::string(glb.begin() + bin_at, glb.end()));
    message = parse_error(ModelFormat::kGltf, std::string(bad_glb.begin(), bad_glb.end()));
    EXPECT_EQ(message.rfind("test", 0), 0u) << pointer << ": " << message;
  }
}

// The glTF sample models' Draco 2CylinderEngine (made by Draco's authors, not by us) against the
// uncompressed one: the same objects in the same order with the same names, each with the
// uncompressed triangles less those with two corners at one place (Draco's encoder drops them), and
// bounds within the stream's quantisation.
TEST(ImportGltf, DracoSampleEngineMatchesTheUncompressedOne) {
  const std::vector<Object> plain = import_model(assimp_model("glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb")).objects;
  const std::vector<Object> draco = import_model(assimp_model("glTF2/draco/2CylinderEngine.gltf")).objects;
  ASSERT_EQ(draco.size(), plain.size());
  ASSERT_GT(plain.size(), 100u);
  size_t dropped = 0;
  for (size_t i = 0; i < plain.size(); ++i) {
    const std::vector<uint32_t>& x = plain[i].mesh.indices;
    size_t proper = 0;
    const std::vector<Vec3>& p = plain[i].mesh.positions;
    for (size_t t = 0; t + 2 < x.size(); t += 3) proper += p[x[t]] != p[x[t + 1]] && p[x[t + 1]] != p[x[t + 2]] && p[x[t]] != p[x[t + 2]];
    dropped += plain[i].mesh.triangle_count() - proper;
    EXPECT_EQ(draco[i].name, plain[i].name);
    EXPECT_EQ(draco[i].mesh.triangle_count(), proper) << plain[i].name;
    const float size = glm::length(plain[i].bounds.max - plain[i].bounds.min);
    EXPECT_LT(glm::length(draco[i].bounds.min - plain[i].bounds.min), 1e-3f * size + 1e-3f) << plain[i].name;
    EXPECT_LT(glm::length(draco[i].bounds.max - plain[i].bounds.max), 1e-3f * size + 1e-3f) << plain[i].name;
  }
  EXPECT_GT(dropped, 0u) << "the oracle's degenerate-triangle rule was exercised";
}

// A 2-million-triangle height field (1001 × 1001 vertices) into patches of at most 16,384
// triangles: each in bounds, together exactly the mesh's triangles, vertices and normals.
TEST(ImportPatches, LargeMeshIsPartitionedIntoBoundedPatches) {
  constexpr uint32_t kSide = 1001;
  Object big;
  big.id = 4;
  big.name = "scan";
  for (uint32_t z = 0; z < kSide; ++z)
    for (uint32_t x = 0; x < kSide; ++x) big.mesh.positions.emplace_back(float(x), std::sin(x * 0.01f) * std::cos(z * 0.013f), float(z));
  for (uint32_t z = 0; z + 1 < kSide; ++z)
    for (uint32_t x = 0; x + 1 < kSide; ++x) {
      const uint32_t v = z * kSide + x;
      big.mesh.indices.insert(big.mesh.indices.end(), {v, v + kSide, v + 1, v + 1, v + kSide, v + kSide + 1});
    }
  compute_normals(big.mesh);
  const Mesh original = big.mesh;
  ASSERT_EQ(original.triangle_count(), 2000000u);
  // A triangle as its three original vertex indices, rotated to start at the smallest.
  const auto key = [](uint32_t a, uint32_t b, uint32_t c) {
    while (a > b || a > c) std::tie(a, b, c) = std::tuple(b, c, a);
    return uint64_t(a) << 42 | uint64_t(b) << 21 | c;
  };
  std::vector<uint64_t> expected, got;
  for (size_t t = 0; t < original.triangle_count(); ++t)
    expected.push_back(key(original.indices[3 * t], original.indices[3 * t + 1], original.indices[3 * t + 2]));
  const std::vector<Object> patches = split_into_patches(std::move(big), 16384);
  EXPECT_GE(patches.size(), 2000000u / 16384);
  for (size_t k = 0; k < patches.size(); ++k) {
    const Object& p = patches[k];
    EXPECT_LE(p.mesh.triangle_count(), 16384u);
    EXPECT_GE(p.mesh.triangle_count(), 16384u / 2);
    EXPECT_EQ(p.id, 4u);
    EXPECT_EQ(p.name, "scan#" + std::to_string(k));
    EXPECT_EQ(p.bounds.min, bounds_of(p.mesh).min);
    EXPECT_EQ(p.bounds.max, bounds_of(p.mesh).max);
    std::vector<uint32_t> index_of(p.mesh.positions.size());
    for (size_t v = 0; v < p.mesh.positions.size(); ++v) {
      const Vec3& q = p.mesh.positions[v];
      index_of[v] = uint32_t(q.z) * kSide + uint32_t(q.x);
      ASSERT_EQ(q, original.positions[index_of[v]]);
      ASSERT_EQ(p.mesh.normals[v], original.normals[index_of[v]]);
    }
    for (size_t t = 0; t < p.mesh.triangle_count(); ++t)
      got.push_back(key(index_of[p.mesh.indices[3 * t]], index_of[p.mesh.indices[3 * t + 1]], index_of[p.mesh.indices[3 * t + 2]]));
  }
  std::sort(expected.begin(), expected.end());
  std::sort(got.begin(), got.end());
  EXPECT_TRUE(got == expected) << got.size() << " triangles in patches against " << expected.size();
  // Small meshes pass through whole.
  Object small;
  small.mesh = test::box_mesh({{0, 0, 0}, {1, 1, 1}});
  EXPECT_EQ(split_into_patches(small, 12).size(), 1u);
  EXPECT_EQ(split_into_patches(small, 5).size(), 4u);
}

// --- the command ---------------------------------------------------------------------------

// --up, --scale, --offset and --place grid, read back from the scene written.
TEST(ImportCommand, PlacesModelsAsAsked) {
  TempDir dir;
  const std::string tetra = cgal_mesh("colored_tetra.ply"), cow = cgal_mesh("cow.off");
  const Aabb t = import_model(tetra).objects.at(0).bounds;
  const auto bounds_after = [&](const std::string& options, size_t object) {
    const std::string scene = dir.file("p.cwscene");
    const auto r = test::run_cellwalk("import " + options + " -o " + scene);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return SceneReader(scene).read_object(ObjectId(object)).bounds;
  };
  const Aabb z_up = bounds_after(tetra + " --up z", 0);
  EXPECT_NEAR(z_up.min.y, t.min.z, 1e-5);
  EXPECT_NEAR(z_up.max.z, -t.min.y, 1e-5);
  const Aabb moved = bounds_after(tetra + " --scale 2 --offset 1,-2,3", 0);
  EXPECT_NEAR(moved.min.x, 2 * t.min.x + 1, 1e-5);
  EXPECT_NEAR(moved.max.y, 2 * t.max.y - 2, 1e-5);
  EXPECT_NEAR(moved.max.z, 2 * t.max.z + 3, 1e-5);
  // Two models side by side on the ground, not overlapping.
  const Aabb first = bounds_after(tetra + " " + cow + " --place grid", 0);
  const Aabb second = bounds_after(tetra + " " + cow + " --place grid", 1);
  EXPECT_NEAR(first.min.y, 0, 1e-5);
  EXPECT_NEAR(second.min.y, 0, 1e-5);
  EXPECT_GT(second.min.x, first.max.x);
  const auto split = test::run_cellwalk("import " + cow + " --patch-triangles 1000 --json -o " + dir.file("c.cwscene"));
  ASSERT_EQ(split.exit_code, 0) << split.output;
  const nlohmann::json j = nlohmann::json::parse(split.output);
  EXPECT_EQ(j["split_into_patches"], 1);
  EXPECT_GE(j["objects"].get<int>(), 6);
  const SceneReader scene(dir.file("c.cwscene"));
  for (ObjectId id = 0; id < scene.object_count(); ++id) EXPECT_LE(scene.read_object(id).mesh.triangle_count(), 1000u);
  for (const char* bad : {"--up x", "--offset 1,2", "--place row", "--scale 0", "--offset 1,2,nan"}) {
    const auto r = test::run_cellwalk("import " + tetra + " " + bad + " -o " + dir.file("bad.cwscene"));
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << bad << ": " << r.output;
  }
}

TEST(ImportCommand, WritesASceneAndCounts) {
  TempDir dir;
  const auto ok = test::run_cellwalk("import " + cgal_mesh("bunny00.off") + " " +
                                     cgal_mesh("colored_tetra.ply") + " -o " +
                                     dir.file("s.cwscene") + " --obj " + dir.file("s.obj"));
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  // The bunny is split into 8 patches of 9,426 triangles (at most 16,384 each by default).
  EXPECT_EQ(ok.output.rfind("imported 9 objects, 75412 triangles, ", 0), 0u) << ok.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("s.cwscene")));
  size_t exported = 0;
  for (const Object& o : import_model(dir.file("s.obj")).objects) exported += o.mesh.triangle_count();
  EXPECT_EQ(exported, 75412u);

  const auto json = test::run_cellwalk("import " + cgal_mesh("colored_tetra.ply") + " -o " +
                                       dir.file("t.cwscene") + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  EXPECT_EQ(nlohmann::json::parse(json.output)["triangles"], 4);
}

TEST(ImportCommand, BrokenFileExitsNonZeroWithOneLineNamingIt) {
  TempDir dir;
  const std::string broken = source_path("tests/data/broken/truncated.off");
  const auto r = test::run_cellwalk("import " + broken + " -o " + dir.file("s.cwscene"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_NE(r.output.find(broken), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("s.cwscene")));
}

// Issue 13, item 6: such a model once imported, built and gave a path of NaNs.
TEST(ImportCommand, ObjWithCoordinatesNearFloatsLimitIsRefused) {
  TempDir dir;
  const std::string model = dir.file("m.obj");
  std::ofstream(model) << "v 0 0 0\nv 3e38 0 0\nv -3e38 3e38 0\nf 1 2 3\n";
  const auto r = test::run_cellwalk("import " + model + " -o " + dir.file("s.cwscene"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "cellwalk: " + model + ": vertex 1 (3e+38, 0, 0) has a coordinate beyond 1e7 m, the largest "
                      "cellwalk handles; rescale the model (e.g. to metres) or move it nearer the origin\n");
  EXPECT_FALSE(std::filesystem::exists(dir.file("s.cwscene")));
}

}  // namespace
}  // namespace cellwalk
