// Seed 004 (Zheng), digest §4 "Base mesh and files": the VDR model file, written and read with
// every byte checked. Byte layout: docs/format.md, "VDR model file".
#include "cellwalk/systems/vdr/vdr_file.hpp"

#include <xxhash.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "core/bytes.hpp"

namespace cellwalk::vdr {
namespace {

constexpr std::array<char, 8> kMagic = {'C', 'W', 'V', 'D', 'R', '\r', '\n', 0x1A};
constexpr uint32_t kVersion = 1;
// Far above what the in-core builder makes; bounds what a header may make a reader allocate
// before the file's length has been checked against it.
constexpr uint64_t kMaxCount = 1ull << 31;

struct Header {
  uint32_t dag_kind, base_vertices, base_triangles, vsplits, adjusted, reserved;
  uint64_t edges;
};

template <typename T>
void put_all(ByteWriter& w, const std::vector<T>& v) {
  w.put_array(std::span<const T>(v));
}

void check_finite(ByteReader& r, std::span<const float> values, std::string_view what, float lo, float hi) {
  for (float v : values)
    if (!std::isfinite(v) || v < lo || v > hi)
      r.error(std::string(what) + " holds " + std::to_string(v) + ", outside [" + std::to_string(lo) + ", " +
              std::to_string(hi) + "]: the file is damaged; rebuild it with cellwalk vdr-build");
}

std::vector<Vec3> get_vec3s(ByteReader& r, uint64_t count, std::string_view what) {
  std::vector<float> raw = r.get_array<float>(3 * count, what);
  check_finite(r, raw, what, -kMaxCoordinate, kMaxCoordinate);
  std::vector<Vec3> out(count);
  if (count) std::memcpy(out.data(), raw.data(), raw.size() * sizeof(float));
  return out;
}

std::vector<uint32_t> get_offsets(ByteReader& r, uint32_t n, uint64_t total, std::string_view what) {
  std::vector<uint32_t> o = r.get_array<uint32_t>(uint64_t(n) + 1, what);
  if (o.front() != 0 || o.back() != total) r.error(std::string(what) + " do not run from 0 to " + std::to_string(total));
  for (uint32_t i = 0; i < n; ++i)
    if (o[i] > o[i + 1]) r.error(std::string(what) + " decrease at " + std::to_string(i));
  return o;
}

Header get_header(ByteReader& r) {
  std::array<char, 8> magic{};
  for (char& c : magic) c = r.get<char>("magic");
  if (magic != kMagic) r.error("not a cellwalk VDR model file (wrong magic); make one with cellwalk vdr-build");
  const uint32_t version = r.get<uint32_t>("version");
  if (version != kVersion)
    r.error("version " + std::to_string(version) + " is not " + std::to_string(kVersion) + "; rebuild it with cellwalk vdr-build");
  Header h{};
  h.dag_kind = r.get<uint32_t>("DAG kind");
  h.base_vertices = r.get<uint32_t>("base vertex count");
  h.base_triangles = r.get<uint32_t>("base triangle count");
  h.vsplits = r.get<uint32_t>("vsplit count");
  h.adjusted = r.get<uint32_t>("adjusted triangle count");
  h.reserved = r.get<uint32_t>("reserved");
  h.edges = r.get<uint64_t>("edge count");
  if (h.dag_kind > 2) r.error("DAG kind " + std::to_string(h.dag_kind) + " is not 0, 1 or 2");
  if (h.base_triangles == 0) r.error("the base mesh has no triangle");
  for (uint64_t c : std::initializer_list<uint64_t>{uint64_t(h.base_vertices) + h.vsplits, uint64_t(h.base_triangles) + 2 * uint64_t(h.vsplits),
                     uint64_t(h.adjusted), h.edges})
    if (c > kMaxCount) r.error("a count of " + std::to_string(c) + " is over the reader's limit");
  return h;
}

[[noreturn]] void damaged(ByteReader& r, const std::string& what) {
  r.error(what + ": the file is damaged; rebuild it with cellwalk vdr-build");
}

// Applies every vsplit in order (the mesh_with_splits oracle, checked): each id must exist when
// it is used, and each adjusted triangle must hold v_p then.
void check_refinement(ByteReader& r, const ProgressiveMesh& pm) {
  for (uint32_t v : pm.base_indices)
    if (v >= pm.base_vertex_count) damaged(r, "a base triangle uses vertex " + std::to_string(v) + ", not in the base");
  std::vector<std::array<uint32_t, 3>> slots(pm.triangle_slots(), {kNone, kNone, kNone});
  for (uint32_t t = 0; t < pm.base_triangle_count; ++t)
    slots[t] = {pm.base_indices[3 * t], pm.base_indices[3 * t + 1], pm.base_indices[3 * t + 2]};
  for (uint32_t i = 0; i < pm.vsplit_count(); ++i) {
    const uint32_t c = pm.v_c(i), p = pm.v_p[i], l = pm.v_l[i], rr = pm.v_r[i];
    const std::string at = "vsplit " + std::to_string(i);
    if (p >= c || (l != kNone && (l >= c || l == p)) || (rr != kNone && (rr >= c || rr == p)) || (l == kNone && rr == kNone))
      damaged(r, at + " uses a vertex not yet made (or none on either side)");
    if (l != kNone) slots[pm.f_l(i)] = {p, c, l};
    if (rr != kNone) slots[pm.f_r(i)] = {c, p, rr};
    for (uint32_t t : pm.adjusted_of(i)) {
      if (t >= pm.f_l(i)) damaged(r, at + " adjusts triangle " + std::to_string(t) + ", not yet made");
      auto it = std::find(slots[t].begin(), slots[t].end(), p);
      if (it == slots[t].end()) damaged(r, at + " adjusts triangle " + std::to_string(t) + ", which does not hold v_p");
      *it = c;
    }
  }
}

void check_dag(ByteReader& r, const ProgressiveMesh& pm, const VsplitDag& dag) {
  std::vector<uint32_t> potential;
  for (uint32_t i = 0; i < dag.node_count(); ++i) {
    potential_parents(pm, i, potential);
    const auto parents = dag.parents(i);
    for (size_t k = 0; k < parents.size(); ++k)
      if ((k > 0 && parents[k] <= parents[k - 1]) ||
          !std::binary_search(potential.begin(), potential.end(), parents[k], std::greater<>()))
        damaged(r, "DAG node " + std::to_string(i) + " has parent " + std::to_string(parents[k]) +
                ", not one of its potential parents in order");
  }
  if (dag.kind == DagKind::kNonRedundant) return;  // rebuilding it is quadratic: the subset check stands
  const VsplitDag again = build_vsplit_dag(pm, dag.kind);
  if (again.in_edges != dag.in_edges || again.in_offsets != dag.in_offsets)
    damaged(r, "the " + dag_kind_name(dag.kind) + " DAG's edges are not the ones its progressive mesh gives");
}

}  // namespace

std::vector<uint8_t> encode_vdr(const ProgressiveMesh& pm, const VsplitDag& dag) {
  ByteWriter w;
  for (char c : kMagic) w.put(c);
  w.put(kVersion);
  w.put(static_cast<uint32_t>(dag.kind));
  w.put(pm.base_vertex_count);
  w.put(pm.base_triangle_count);
  w.put(pm.vsplit_count());
  w.put(static_cast<uint32_t>(pm.adjusted.size()));
  w.put(uint32_t{0});
  w.put(static_cast<uint64_t>(dag.edge_count()));
  put_all(w, pm.positions);
  put_all(w, pm.normals);
  put_all(w, pm.base_indices);
  put_all(w, pm.v_p);
  put_all(w, pm.v_l);
  put_all(w, pm.v_r);
  put_all(w, pm.error);
  put_all(w, pm.adjusted_offsets);
  put_all(w, pm.adjusted);
  put_all(w, dag.in_offsets);
  put_all(w, dag.in_edges);
  put_all(w, dag.attributes.rad);
  put_all(w, dag.attributes.cone_sin);
  put_all(w, dag.attributes.ap_err);
  w.put(static_cast<uint64_t>(XXH3_64bits(w.bytes().data(), w.size())));
  return std::move(w.bytes());
}

void write_vdr_file(const std::string& path, const ProgressiveMesh& pm, const VsplitDag& dag) {
  AtomicFile file(path);
  file.write(encode_vdr(pm, dag));
  file.commit();
}

VdrModel decode_vdr(std::span<const uint8_t> bytes, const std::string& where) {
  if (bytes.size() < sizeof(uint64_t)) fail(where, "is too short to be a VDR model file (" + std::to_string(bytes.size()) + " bytes)");
  const size_t body = bytes.size() - sizeof(uint64_t);
  uint64_t stored;
  std::memcpy(&stored, bytes.data() + body, sizeof stored);
  ByteReader r(bytes.first(body), where);
  const Header h = get_header(r);  // names a wrong kind of file before the checksum does
  if (XXH3_64bits(bytes.data(), body) != stored)
    fail(where, "checksum mismatch: the file is damaged or truncated; rebuild it with cellwalk vdr-build");
  VdrModel m;
  ProgressiveMesh& pm = m.pm;
  pm.base_vertex_count = h.base_vertices;
  pm.base_triangle_count = h.base_triangles;
  const uint64_t n = h.vsplits, vertices = uint64_t(h.base_vertices) + n;
  pm.positions = get_vec3s(r, vertices, "positions");
  pm.normals = get_vec3s(r, vertices, "normals");
  pm.base_indices = r.get_array<uint32_t>(3ull * h.base_triangles, "base triangles");
  pm.v_p = r.get_array<uint32_t>(n, "v_p");
  pm.v_l = r.get_array<uint32_t>(n, "v_l");
  pm.v_r = r.get_array<uint32_t>(n, "v_r");
  pm.error = r.get_array<float>(n, "errors");
  check_finite(r, pm.error, "errors", 0, std::numeric_limits<float>::max());
  pm.adjusted_offsets = get_offsets(r, h.vsplits, h.adjusted, "adjusted offsets");
  pm.adjusted = r.get_array<uint32_t>(h.adjusted, "adjusted triangles");
  check_refinement(r, pm);
  VsplitDag& dag = m.dag;
  dag.kind = static_cast<DagKind>(h.dag_kind);
  dag.in_offsets = get_offsets(r, h.vsplits, h.edges, "DAG offsets");
  dag.in_edges = r.get_array<uint32_t>(h.edges, "DAG edges");
  check_dag(r, pm, dag);
  dag.attributes.rad = r.get_array<float>(n, "radii");
  check_finite(r, dag.attributes.rad, "radii", 0, 4 * kMaxCoordinate);
  dag.attributes.cone_sin = r.get_array<float>(n, "cone sines");
  check_finite(r, dag.attributes.cone_sin, "cone sines", 0, 1);
  dag.attributes.ap_err = r.get_array<float>(n, "ap_err");
  check_finite(r, dag.attributes.ap_err, "ap_err", 0, std::numeric_limits<float>::max());
  if (r.remaining() != 0) r.error(std::to_string(r.remaining()) + " bytes follow the last array");
  derive_children(dag);  // the out-edges are not stored: they are the in-edges turned round
  for (const Vec3& p : pm.positions) m.bounds.extend(p);
  return m;
}

VdrModel read_vdr_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail(path, "is a directory, not a VDR model file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno) + "; make one with cellwalk vdr-build");
  std::vector<uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) fail(path, "read failed");
  return decode_vdr(bytes, path);
}

}  // namespace cellwalk::vdr
