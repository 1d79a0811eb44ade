// The VDR model file (`.cwvdr`, docs/format.md "VDR model file"): one model's progressive mesh
// and vsplit DAG with its attributes, as the server of seed 004 ch. 3–6 reads it. Little-endian,
// one header, arrays in a fixed order, an XXH3 checksum of every byte before it.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/systems/vdr/progressive_mesh.hpp"
#include "cellwalk/systems/vdr/vsplit_dag.hpp"

namespace cellwalk::vdr {

struct VdrModel {
  ProgressiveMesh pm;
  VsplitDag dag;
  Aabb bounds;  // of every vertex
};

// Serialises and writes through AtomicFile: an existing file at `path` survives any failure.
void write_vdr_file(const std::string& path, const ProgressiveMesh& pm, const VsplitDag& dag);
std::vector<uint8_t> encode_vdr(const ProgressiveMesh& pm, const VsplitDag& dag);

// Parses a model and checks all of it: the checksum, then that every id is in range and created
// before it is used, that applying every vsplit in order finds each adjusted triangle holding
// v_p, that every DAG edge is a potential parent (and, for the full and mini kinds, that the
// edges are exactly what the builder makes), and that every number is finite and in its range.
// Throws Error "<where>@<offset>: ..." or "<where>: ..." on anything else; never crashes.
VdrModel decode_vdr(std::span<const uint8_t> bytes, const std::string& where);
VdrModel read_vdr_file(const std::string& path);

}  // namespace cellwalk::vdr
