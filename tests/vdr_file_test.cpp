// The VDR model file (docs/format.md "VDR model file") and `cellwalk vdr-build`: a round trip
// keeps every array; damage of any kind is one Error line, checksum or structure.
#include <gtest/gtest.h>
#include <xxhash.h>

#include <cstring>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/systems/vdr/vdr_file.hpp"
#include "test_support.hpp"

namespace cellwalk::vdr {
namespace {

struct CowModel {
  ProgressiveMesh pm = build_progressive_mesh(import_model(test::cgal_mesh("cow.off")).objects[0].mesh, {.base_triangles = 100}, "cow");
  VsplitDag dag = build_vsplit_dag(pm, DagKind::kMiniRedundant);
};

const CowModel& cow_model() {
  static const CowModel model;
  return model;
}

// Fixes the trailing checksum after an edit, so the structural checks are what sees it.
void reseal(std::vector<uint8_t>& bytes) {
  const uint64_t sum = XXH3_64bits(bytes.data(), bytes.size() - 8);
  std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
}

std::string decode_error(const std::vector<uint8_t>& bytes) {
  try {
    decode_vdr(bytes, "m.cwvdr");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(VdrFile, RoundTripKeepsEveryArray) {
  const CowModel& m = cow_model();
  test::TempDir dir;
  write_vdr_file(dir.file("cow.cwvdr"), m.pm, m.dag);
  const VdrModel back = read_vdr_file(dir.file("cow.cwvdr"));
  EXPECT_EQ(back.pm.base_vertex_count, m.pm.base_vertex_count);
  EXPECT_EQ(back.pm.base_triangle_count, m.pm.base_triangle_count);
  EXPECT_EQ(back.pm.positions, m.pm.positions);
  EXPECT_EQ(back.pm.normals, m.pm.normals);
  EXPECT_EQ(back.pm.base_indices, m.pm.base_indices);
  EXPECT_EQ(back.pm.v_p, m.pm.v_p);
  EXPECT_EQ(back.pm.v_l, m.pm.v_l);
  EXPECT_EQ(back.pm.v_r, m.pm.v_r);
  EXPECT_EQ(back.pm.error, m.pm.error);
  EXPECT_EQ(back.pm.adjusted_offsets, m.pm.adjusted_offsets);
  EXPECT_EQ(back.pm.adjusted, m.pm.adjusted);
  EXPECT_EQ(back.dag.kind, m.dag.kind);
  EXPECT_EQ(back.dag.in_offsets, m.dag.in_offsets);
  EXPECT_EQ(back.dag.in_edges, m.dag.in_edges);
  EXPECT_EQ(back.dag.out_offsets, m.dag.out_offsets);
  EXPECT_EQ(back.dag.out_edges, m.dag.out_edges);
  EXPECT_EQ(back.dag.attributes.rad, m.dag.attributes.rad);
  EXPECT_EQ(back.dag.attributes.cone_sin, m.dag.attributes.cone_sin);
  EXPECT_EQ(back.dag.attributes.ap_err, m.dag.attributes.ap_err);
}

TEST(VdrFile, AnyFlippedByteOrTruncationIsOneErrorLine) {
  const std::vector<uint8_t> good = encode_vdr(cow_model().pm, cow_model().dag);
  for (size_t at = 0; at < good.size(); at += 997) {
    std::vector<uint8_t> bad = good;
    bad[at] ^= 0x40;
    const std::string e = decode_error(bad);
    ASSERT_FALSE(e.empty()) << "flip at " << at;
    EXPECT_EQ(e.find('\n'), std::string::npos);
  }
  for (size_t keep : {size_t(0), size_t(5), size_t(40), good.size() / 2, good.size() - 1})
    EXPECT_FALSE(decode_error(std::vector<uint8_t>(good.begin(), good.begin() + keep)).empty()) << keep;
  std::vector<uint8_t> other = good;
  other[0] = 'X';
  EXPECT_NE(decode_error(other).find("not a cellwalk VDR model file"), std::string::npos) << decode_error(other);
}

// Edits with a right checksum: each structural check must catch what it guards.
TEST(VdrFile, StructuralDamageBehindAGoodChecksumIsCaught) {
  const ProgressiveMesh& pm = cow_model().pm;
  const VsplitDag& dag = cow_model().dag;
  const std::vector<uint8_t> good = encode_vdr(pm, dag);
  const size_t n = pm.vsplit_count();
  const size_t v_p = 44 + 2 * 12 * size_t(pm.vertex_count()) + 12 * size_t(pm.base_triangle_count);
  const size_t adjusted = v_p + 16 * n + 4 * (n + 1);
  const size_t edges = adjusted + 4 * pm.adjusted.size() + 4 * (n + 1);
  const size_t radii = edges + 4 * dag.edge_count();
  const auto edit_u32 = [&](size_t offset, uint32_t value) {
    std::vector<uint8_t> bad = good;
    std::memcpy(bad.data() + offset, &value, 4);
    reseal(bad);
    return decode_error(bad);
  };
  // v_p of vsplit 5 names the vertex vsplit 5 itself makes.
  EXPECT_NE(edit_u32(v_p + 4 * 5, pm.v_c(5)).find("vsplit 5"), std::string::npos);
  // The last adjusted triangle of the last vsplit made another that does not hold its v_p.
  uint32_t other = 0;
  while (std::find(pm.adjusted.begin() + pm.adjusted_offsets[n - 1], pm.adjusted.end(), other) != pm.adjusted.end()) ++other;
  EXPECT_NE(edit_u32(adjusted + 4 * (pm.adjusted.size() - 1), other).find("v_p"), std::string::npos);
  // The last DAG edge pointed at node 0: not a potential parent, or not the mini builder's.
  EXPECT_NE(edit_u32(edges + 4 * (dag.edge_count() - 1), 0).find("DAG"), std::string::npos);
  // A vsplit count in the header one larger than the arrays.
  EXPECT_FALSE(edit_u32(24, static_cast<uint32_t>(n + 1)).empty());
  // A radius made negative.
  float minus = -1.0f;
  uint32_t bits;
  std::memcpy(&bits, &minus, 4);
  EXPECT_NE(edit_u32(radii, bits).find("radii"), std::string::npos);
}

nlohmann::json vdr_json(const std::string& output) {
  const size_t start = output.find('{');
  return start == std::string::npos ? nlohmann::json() : nlohmann::json::parse(output.substr(start), nullptr, false);
}

TEST(VdrBuildCommand, BuildsAModelAndRefusesWhatItCannotUse) {
  test::TempDir dir;
  const std::string out = dir.file("cow.cwvdr");
  const auto ok = test::run_cellwalk("vdr-build " + test::cgal_mesh("cow.off") + " -o " + out + " --base-triangles 100 --json");
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  const nlohmann::json j = vdr_json(ok.output);
  ASSERT_TRUE(j.is_object()) << ok.output;
  EXPECT_EQ(j["input_triangles"].get<uint32_t>(), 5804u);
  EXPECT_EQ(j["vsplits"].get<uint32_t>() + j["base_vertices"].get<uint32_t>(), j["vertices"].get<uint32_t>());
  EXPECT_EQ(read_vdr_file(out).pm.vsplit_count(), j["vsplits"].get<uint32_t>());
  const auto before = test::slurp(out);
  for (const std::string& bad : {"vdr-build " + out + " -o " + out,  // not a model, and itself
                                 "vdr-build " + test::cgal_mesh("cow.off") + " -o " + out + " --dag most",
                                 "vdr-build " + test::cgal_mesh("cow.off") + " -o " + out + " --base-triangles 0",
                                 "vdr-build " + dir.file("none.off") + " -o " + out}) {
    const auto r = test::run_cellwalk(bad);
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_FALSE(r.output.empty()) << bad;
  }
  EXPECT_EQ(test::slurp(out), before);  // every refusal left the good file alone
}

}  // namespace
}  // namespace cellwalk::vdr
