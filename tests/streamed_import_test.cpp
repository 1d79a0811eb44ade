// Importing a model larger than memory (issue 16, src/scene/streamed_import.cpp): the patches
// against the import in memory (the oracle: the same triangles, the whole mesh's normals), a
// partition that is spatial, degenerate input, damaged files, and the process's peak memory
// from outside on a file larger than the memory the import is given.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <numeric>
#include <random>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

using test::TempDir;

struct PlainMesh {
  std::vector<Vec3> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
};

// An n × n height field (y up), its vertices in a shuffled order when `seed` is not 0, so that
// the file's order says nothing about where a vertex lies: only a spatial partition then gives
// compact patches. (Shuffled, a field much larger than the vertex cache is slow to read: every
// triangle's corners are then in blocks of their own.)
PlainMesh height_field(int n, uint32_t seed) {
  std::vector<uint32_t> slot(size_t(n) * n);
  std::iota(slot.begin(), slot.end(), 0u);
  if (seed != 0) {
    std::mt19937 rng(seed);
    std::shuffle(slot.begin(), slot.end(), rng);
  }
  PlainMesh m;
  m.positions.resize(slot.size());
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x)
      m.positions[slot[size_t(z) * n + x]] = Vec3(x, 3.0f * std::sin(0.05f * x) * std::cos(0.07f * z), z);
  for (int z = 0; z + 1 < n; ++z)
    for (int x = 0; x + 1 < n; ++x) {
      const uint32_t a = slot[size_t(z) * n + x], b = slot[size_t(z) * n + x + 1], c = slot[size_t(z + 1) * n + x],
                     d = slot[size_t(z + 1) * n + x + 1];
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
  return m;
}

void write_ply(const std::string& path, const PlainMesh& m, bool ascii) {
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\nelement vertex " << m.positions.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << m.triangles.size()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  std::string body;
  for (const Vec3& p : m.positions) {
    if (ascii) body += std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + "\n";
    else body.append(reinterpret_cast<const char*>(&p), sizeof p);
  }
  for (const auto& t : m.triangles) {
    if (ascii) {
      body += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
    } else {
      body += '\x03';
      body.append(reinterpret_cast<const char*>(t.data()), 12);
    }
    if (body.size() > (16 << 20)) {
      out << body;
      body.clear();
    }
  }
  out << body;
}

// A triangle as its corners' positions and normals, from its least corner on (winding kept),
// so that the same triangle compares equal however it is indexed.
using CornerKey = std::array<float, 6>;
using TriangleKey = std::array<CornerKey, 3>;

std::vector<TriangleKey> triangle_keys(const Mesh& mesh) {
  std::vector<TriangleKey> keys;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    TriangleKey k;
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = mesh.indices[3 * t + c];
      // Directions: a file's normals are kept as they are read whole, made unit length streamed.
      const Vec3 p = mesh.positions[v], n = glm::normalize(mesh.normals[v]);
      k[c] = {p.x, p.y, p.z, n.x, n.y, n.z};
    }
    const auto least = std::min_element(k.begin(), k.end(), [](const CornerKey& a, const CornerKey& b) {
      return std::lexicographical_compare(a.begin(), a.begin() + 3, b.begin(), b.begin() + 3);
    });
    std::rotate(k.begin(), least, k.end());
    keys.push_back(k);
  }
  return keys;
}

bool same_positions(const TriangleKey& a, const TriangleKey& b) {
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < 3; ++i)
      if (a[c][i] != b[c][i]) return false;
  return true;
}

bool positions_less(const TriangleKey& a, const TriangleKey& b) {
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < 3; ++i)
      if (a[c][i] != b[c][i]) return a[c][i] < b[c][i];
  return false;
}

struct Streamed {
  std::vector<Object> patches;
  Aabb bounds;
};

Streamed stream(const std::string& file, uint64_t memory, size_t patch_triangles, const Mat4& m = Mat4(1.0f),
                const Vec3& move = Vec3(0.0f)) {
  StreamLimits limits;
  limits.memory_bytes = memory;
  limits.patch_triangles = patch_triangles;
  StreamedModel model(file, m, limits);
  Streamed s;
  s.bounds = model.bounds();
  model.patches(move, [&](Object& o) { s.patches.push_back(o); });
  return s;
}

// The streamed patches hold exactly the triangles of the import in memory, each corner with the
// normal compute_normals gives over the whole mesh; every patch within the bound.
void expect_same_as_in_memory(const std::string& file, const Streamed& s, size_t patch_triangles) {
  const Object whole = import_model(file).objects.at(0);
  std::vector<TriangleKey> expected = triangle_keys(whole.mesh), got;
  for (const Object& patch : s.patches) {
    EXPECT_LE(patch.mesh.triangle_count(), patch_triangles) << patch.name;
    EXPECT_GT(patch.mesh.triangle_count(), 0u) << patch.name;
    EXPECT_EQ(patch.bounds.min, bounds_of(patch.mesh).min);
    const std::vector<TriangleKey> keys = triangle_keys(patch.mesh);
    got.insert(got.end(), keys.begin(), keys.end());
  }
  std::sort(expected.begin(), expected.end(), positions_less);
  std::sort(got.begin(), got.end(), positions_less);
  ASSERT_EQ(got.size(), expected.size());
  size_t wrong_positions = 0, wrong_normals = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    if (!same_positions(got[i], expected[i])) {
      ++wrong_positions;
      continue;
    }
    for (int c = 0; c < 3; ++c)
      for (int k = 3; k < 6; ++k)
        if (std::abs(got[i][c][k] - expected[i][c][k]) > 1e-5f) {
          ++wrong_normals;
          c = 3;
          break;
        }
  }
  EXPECT_EQ(wrong_positions, 0u);
  EXPECT_EQ(wrong_normals, 0u);
}

TEST(StreamedImport, PatchesHoldTheMeshsTrianglesWithTheWholeMeshsNormals) {
  TempDir dir;
  const PlainMesh field = height_field(120, 7);  // 28,322 triangles
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(ascii ? "ascii" : "binary");
    const std::string file = dir.file(ascii ? "field-ascii.ply" : "field.ply");
    write_ply(file, field, ascii);
    // 1 MiB: buckets of at most 2,730 triangles, so the 28,322 go through two partition steps.
    const Streamed s = stream(file, 1 << 20, 300);
    EXPECT_GE(s.patches.size(), field.triangles.size() / 300);
    expect_same_as_in_memory(file, s, 300);
    // Spatial: with the vertices shuffled in the file, only a partition by place keeps each
    // patch within a small part of the field.
    for (const Object& patch : s.patches) {
      const Vec3 size = patch.bounds.size();
      EXPECT_LT(size.x * size.z, 0.05f * 119 * 119) << patch.name << " spans " << size.x << " × " << size.z;
    }
    std::vector<std::string> names;
    for (const Object& patch : s.patches) names.push_back(patch.name);
    std::sort(names.begin(), names.end());
    EXPECT_EQ(std::unique(names.begin(), names.end()), names.end());
    EXPECT_EQ(s.patches.front().name, "field" + std::string(ascii ? "-ascii" : "") + "#0");
  }
}

TEST(StreamedImport, RealScansMatchTheirImportInMemory) {
  // assimp's Wuson (3,732 triangles, extra properties, a free-text header line), CGAL's bunny
  // and its coloured tetrahedron (normals and colours from the file).
  const Streamed wuson = stream(test::assimp_model("PLY/Wuson.ply"), 1 << 20, 100);
  expect_same_as_in_memory(test::assimp_model("PLY/Wuson.ply"), wuson, 100);
  // CGAL's bunny as OFF: 75,408 triangles through a partition step.
  const Streamed bunny = stream(test::cgal_mesh("bunny00.off"), 1 << 20, 2000);
  EXPECT_GT(bunny.patches.size(), 75408u / 2000);
  expect_same_as_in_memory(test::cgal_mesh("bunny00.off"), bunny, 2000);
  const Streamed tetra = stream(test::cgal_mesh("colored_tetra.ply"), 1 << 20, 100);
  expect_same_as_in_memory(test::cgal_mesh("colored_tetra.ply"), tetra, 100);
  const Object whole = import_model(test::cgal_mesh("colored_tetra.ply")).objects.at(0);
  ASSERT_EQ(tetra.patches.size(), 1u);
  std::vector<Rgba8> a = whole.mesh.colors, b = tetra.patches[0].mesh.colors;
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
}

// OBJ streamed is its geometry alone: one mesh of its faces, whatever its groups (read whole,
// they would be objects of their own, each with its own normals).
TEST(StreamedImport, ObjGeometryMatchesTheImportInMemory) {
  TempDir dir;
  const PlainMesh field = height_field(60, 5);
  const std::string file = dir.file("field.obj");
  {
    std::ofstream out(file);
    out << "# a height field\nmtllib none.mtl\no field\n";
    for (const Vec3& p : field.positions) out << "v " << p.x << " " << p.y << " " << p.z << "\nvt 0 0\n";
    for (const auto& t : field.triangles)  // 1-based, the second corner relative, with vt
      out << "f " << t[0] + 1 << "/" << t[0] + 1 << " " << int64_t(t[1]) - int64_t(field.positions.size()) << " "
          << t[2] + 1 << "//1\n";
  }
  const Streamed s = stream(file, 1 << 20, 500);
  EXPECT_GT(s.patches.size(), field.triangles.size() / 500);
  expect_same_as_in_memory(file, s, 500);
  // assimp's spider: 19 groups read whole; streamed, the same triangles in patches.
  const std::string spider = test::assimp_model("OBJ/spider.obj");
  size_t whole = 0, streamed = 0;
  for (const Object& o : import_model(spider).objects) whole += o.mesh.triangle_count();
  for (const Object& o : stream(spider, 1 << 20, 500).patches) streamed += o.mesh.triangle_count();
  EXPECT_EQ(streamed, whole);
}

TEST(StreamedImport, PlacementTurnsScalesAndMovesAsImportDoes) {
  TempDir dir;
  const std::string file = dir.file("field.ply");
  write_ply(file, height_field(40, 3), false);
  Placement p;
  p.z_up = true;
  p.scale = 0.5f;
  const Vec3 move(100, 0, -20);
  const Streamed s = stream(file, 1 << 20, 200, placement_matrix(p), move);
  Object whole = import_model(file).objects.at(0);
  place(whole, placement_matrix(p));
  Aabb got;
  for (const Object& patch : s.patches) got.extend(patch.bounds);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(s.bounds.min[a], whole.bounds.min[a], 1e-4f);
    EXPECT_NEAR(got.min[a], whole.bounds.min[a] + move[a], 1e-4f);
    EXPECT_NEAR(got.max[a], whole.bounds.max[a] + move[a], 1e-4f);
  }
}

TEST(StreamedImport, CoincidentTrianglesAreCutInFileOrder) {
  // 6,000 triangles with one centroid: no grid can part them; the partition must still end,
  // with every patch within its bound.
  TempDir dir;
  PlainMesh m;
  for (int i = 0; i < 6000; ++i) {
    const uint32_t v = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
    m.triangles.push_back({v, v + 1, v + 2});
  }
  const std::string file = dir.file("stack.ply");
  write_ply(file, m, false);
  const Streamed s = stream(file, 1 << 20, 500);
  size_t triangles = 0;
  for (const Object& patch : s.patches) {
    EXPECT_LE(patch.mesh.triangle_count(), 500u);
    triangles += patch.mesh.triangle_count();
  }
  EXPECT_EQ(triangles, 6000u);
}

void expect_error(const std::function<void()>& f, const std::string& part) {
  try {
    f();
    ADD_FAILURE() << "no error; expected one with '" << part << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

TEST(StreamedImport, DamagedFilesAndBadSettingsAreNamed) {
  TempDir dir;
  const std::string file = dir.file("field.ply");
  write_ply(file, height_field(30, 1), false);
  std::vector<uint8_t> bytes = test::slurp(file);
  const std::string cut = dir.file("cut.ply");
  test::spit(cut, std::vector<uint8_t>(bytes.begin(), bytes.begin() + long(bytes.size() / 2)));
  expect_error([&] { stream(cut, 1 << 20, 100); }, cut + "@");
  // The last face's last index made 900 (there are 900 vertices).
  std::vector<uint8_t> bad = bytes;
  const uint32_t v = 900;
  std::memcpy(bad.data() + bad.size() - 4, &v, 4);
  const std::string bad_index = dir.file("bad-index.ply");
  test::spit(bad_index, bad);
  expect_error([&] { stream(bad_index, 1 << 20, 100); }, "uses vertex 900 but there are 900 vertices");
  expect_error([&] { stream(test::assimp_model("glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"), 1 << 20, 100); },
               "glTF is not read streamed");
  const std::string bad_obj = dir.file("bad.obj");
  test::spit(bad_obj, {'v', ' ', '0', ' ', '0', ' ', '0', '\n', 'f', ' ', '1', ' ', '2', ' ', '1', '\n'});
  expect_error([&] { stream(bad_obj, 1 << 20, 100); }, bad_obj + ":2: face uses vertex 2 but 1 vertices are defined so far");
  StreamLimits limits;
  limits.temp_dir = dir.file("no-such-folder");
  expect_error([&] { StreamedModel(file, Mat4(1.0f), limits); }, "--temp-dir");
  limits.temp_dir.clear();
  limits.patch_triangles = 0;
  expect_error([&] { StreamedModel(file, Mat4(1.0f), limits); }, "--patch-triangles");
}

// The command on a file larger than the memory it is given: the process's peak, measured by the
// kernel from outside, within its resident memory at start plus --memory; the same file read
// whole goes over that, so the bound is the streaming's doing. A damaged file leaves an
// existing scene as it was.
TEST(ImportCommand, StreamsAModelLargerThanItsMemoryWithinIt) {
  TempDir dir;
  const std::string file = dir.file("terrain.ply");
  write_ply(file, height_field(1500, 0), false);  // 4,494,002 triangles, 85 MB
  const uint64_t file_bytes = std::filesystem::file_size(file);
  constexpr uint64_t kMemory = 32ull << 20;
  ASSERT_GT(file_bytes, 2 * kMemory);

  const std::string scene = dir.file("terrain.cwscene");
  const test::CommandResult streamed =
      test::run_cellwalk("import " + file + " -o " + scene + " --memory 32 --json");
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  const nlohmann::json j = test::json_output(streamed);
  ASSERT_TRUE(j.is_object()) << streamed.output;
  EXPECT_EQ(j.value("streamed", 0), 1);
  EXPECT_EQ(j.value("triangles", uint64_t(0)), 2ull * 1499 * 1499);
  const SceneReader reader(scene);
  EXPECT_EQ(reader.triangle_count(), 2ull * 1499 * 1499);
  for (size_t id = 0; id < reader.object_count(); ++id) EXPECT_LE(reader.entry(ObjectId(id)).triangles, 16384u);
  if (!test::kUnderAddressSanitizer) {
    const uint64_t baseline = j.value("baseline_rss_bytes", uint64_t(0));
    EXPECT_GT(baseline, 0u);
    EXPECT_LE(streamed.max_rss_bytes, baseline + kMemory)
        << "peak " << streamed.max_rss_bytes / 1048576.0 << " MiB, baseline " << baseline / 1048576.0 << " MiB";
    EXPECT_LE(j.value("peak_rss_bytes", uint64_t(0)), baseline + kMemory);
    EXPECT_LT(streamed.max_rss_bytes, file_bytes);
    // Read whole, the same file takes more than the streamed import's bound.
    const test::CommandResult whole =
        test::run_cellwalk("import " + file + " -o " + dir.file("whole.cwscene") + " --memory 4096 --json");
    ASSERT_EQ(whole.exit_code, 0) << whole.output;
    EXPECT_EQ(test::json_output(whole).value("streamed", 1), 0);
    EXPECT_GT(whole.max_rss_bytes, baseline + kMemory);
  }

  // A patch bound above what fits the memory gives smaller patches, not a larger process.
  const test::CommandResult large_patches = test::run_cellwalk("import " + file + " -o " + dir.file("large.cwscene") +
                                                               " --memory 32 --patch-triangles 2000000 --json");
  ASSERT_EQ(large_patches.exit_code, 0) << large_patches.output;
  if (!test::kUnderAddressSanitizer) {
    const uint64_t baseline = test::json_output(large_patches).value("baseline_rss_bytes", uint64_t(0));
    EXPECT_LE(large_patches.max_rss_bytes, baseline + kMemory) << "peak " << large_patches.max_rss_bytes / 1048576.0 << " MiB";
  }
  // Unsplit (--patch-triangles 0), a file under 2 GiB is read whole, as before streaming was.
  const test::CommandResult unsplit = test::run_cellwalk("import " + file + " -o " + dir.file("unsplit.cwscene") +
                                                         " --memory 32 --patch-triangles 0 --json");
  ASSERT_EQ(unsplit.exit_code, 0) << unsplit.output;
  EXPECT_EQ(test::json_output(unsplit).value("streamed", 1), 0);
  EXPECT_EQ(test::json_output(unsplit).value("objects", 0), 1);

  const std::vector<uint8_t> before = test::slurp(scene);
  std::vector<uint8_t> bytes = test::slurp(file);
  bytes.resize(bytes.size() - 1000);
  const std::string cut = dir.file("cut.ply");
  test::spit(cut, bytes);
  const test::CommandResult damaged = test::run_cellwalk("import " + cut + " -o " + scene + " --stream --memory 32");
  EXPECT_NE(damaged.exit_code, 0);
  EXPECT_NE(damaged.output.find(cut + "@"), std::string::npos) << damaged.output;
  EXPECT_EQ(test::slurp(scene), before);
}

// Pages of the mapped file are given back behind the reader in every element, the ones it reads
// past too: a PLY whose 48 MB are mostly an element import does not use is imported within
// 32 MiB. A point cloud streamed is skipped, as read whole, and the import goes on.
TEST(ImportCommand, StreamedImportGivesBackWhatItReadPastAndSkipsPointClouds) {
  TempDir dir;
  const std::string file = dir.file("edges.ply");
  {
    const PlainMesh m = height_field(20, 0);
    std::ofstream out(file, std::ios::binary);
    const uint64_t edges = 6'000'000;
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << m.positions.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nelement edge " << edges
        << "\nproperty int vertex1\nproperty int vertex2\nelement face " << m.triangles.size()
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    out.write(reinterpret_cast<const char*>(m.positions.data()), std::streamsize(m.positions.size() * sizeof(Vec3)));
    const std::vector<int32_t> zeros(2 * edges, 0);
    out.write(reinterpret_cast<const char*>(zeros.data()), std::streamsize(zeros.size() * sizeof(int32_t)));
    for (const auto& t : m.triangles) {
      out.put(3);
      out.write(reinterpret_cast<const char*>(t.data()), 12);
    }
  }
  const std::string points = test::cgal_mesh("b9.ply");  // 22,300 vertices, no face
  const test::CommandResult r = test::run_cellwalk("import " + points + " " + file + " -o " + dir.file("edges.cwscene") +
                                                   " --stream --memory 32 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = test::json_output(r);
  EXPECT_EQ(j.value("streamed", 0), 2);
  EXPECT_EQ(j.value("skipped_without_triangles", 0), 1);
  EXPECT_EQ(j.value("triangles", 0), 2 * 19 * 19);
  if (!test::kUnderAddressSanitizer) {
    EXPECT_LE(r.max_rss_bytes, j.value("baseline_rss_bytes", uint64_t(0)) + (32ull << 20))
        << "peak " << r.max_rss_bytes / 1048576.0 << " MiB";
  }
}

}  // namespace
}  // namespace cellwalk
