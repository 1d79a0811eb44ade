// libFuzzer target for the VDR model file reader (decode_vdr; docs/format.md, "VDR model file").
// The file is a real one, of a small ellipsoid's progressive mesh and mini DAG, edited by the
// input: the first byte 0 takes the rest of the input as the file itself; otherwise the input is
// a truncation (u16, modulo the file's size + 1) and then (u16 offset, u8 xor) edits. The
// checksum is then made right again, so that the structural checks behind it are what is
// tested. Decoding must give a model or a cellwalk::Error; a model must then refine in full on a
// client's selective mesh and cut, with no error and no crash.
#include <xxhash.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/vdr/cut_state.hpp"
#include "cellwalk/systems/vdr/selective_mesh.hpp"
#include "cellwalk/systems/vdr/vdr_file.hpp"
#include "scene/shapes.hpp"

namespace {

using namespace cellwalk;

std::vector<uint8_t> base_file() {
  const Mesh mesh = shapes::ellipsoid(Vec3(1.0f, 2.0f, 1.5f), 12, 8);
  const vdr::ProgressiveMesh pm = vdr::build_progressive_mesh(mesh, {.base_triangles = 8}, "ellipsoid");
  return vdr::encode_vdr(pm, vdr::build_vsplit_dag(pm, vdr::DagKind::kMiniRedundant));
}

std::vector<uint8_t> edited(const std::vector<uint8_t>& file, const uint8_t* data, size_t size) {
  std::vector<uint8_t> out = data[0] == 0 ? std::vector<uint8_t>(data + 1, data + size) : file;
  if (data[0] != 0) {
    if (size >= 3) out.resize((data[1] | size_t(data[2]) << 8) % (file.size() + 1));
    for (size_t i = 3; i + 2 < size && !out.empty(); i += 3)
      out[(data[i] | size_t(data[i + 1]) << 8) % out.size()] ^= data[i + 2];
  }
  if (out.size() >= 8) {
    const uint64_t sum = XXH3_64bits(out.data(), out.size() - 8);
    std::memcpy(out.data() + out.size() - 8, &sum, 8);
  }
  return out;
}

void refine_fully(const vdr::VdrModel& m) {
  const vdr::ProgressiveMesh& pm = m.pm;
  vdr::SelectiveMesh mesh(std::span(pm.positions).first(pm.base_vertex_count),
                          std::span(pm.normals).first(pm.base_vertex_count), pm.base_indices);
  vdr::CutState cut(m.dag);
  for (uint32_t i = 0; i < pm.vsplit_count(); ++i) {
    if (!cut.can_split(i)) std::abort();  // in id order every parent is split first
    cut.split(i);
    mesh.vsplit({i, pm.v_p[i], pm.v_l[i], pm.v_r[i], pm.positions[pm.v_c(i)], pm.normals[pm.v_c(i)], pm.adjusted_of(i)});
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<uint8_t> file = base_file();
  if (size == 0) return 0;
  vdr::VdrModel model;
  try {
    model = vdr::decode_vdr(edited(file, data, size), "input.cwvdr");
  } catch (const Error&) {
    return 0;
  }
  refine_fully(model);  // a model that decodes must be usable: an Error here is a bug
  return 0;
}
