// Compressed storage of one mesh: quantised positions and octahedral normals, packed with
// meshoptimizer's vertex and index codecs, optionally zstd on top.
// Seed: the world store of DESIGN.md (000 HDoV thesis §4 and 001 vLOD §2.4 store geometry
// per object on disk); codecs: Arseny Kapoulkine, meshoptimizer vertex/index codecs;
// Meyer et al., On floating-point normal vectors, 2010 (octahedral encoding).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "cellwalk/scene/mesh.hpp"

namespace cellwalk {

struct CodecParams {
  // Positions are quantised to this many bits per axis over the mesh's box, 1..16.
  // Decoded positions lie within box_size / (2^bits - 1) / 2 of the originals on each axis
  // (plus float rounding, about 1e-7 of the coordinates' magnitude).
  int position_bits = 16;
  // Normals are octahedral, this many bits per component, 2..16 (stored in 2×8 bits up to
  // 8, else 2×16).
  int normal_bits = 8;
  bool zstd = false;
  int zstd_level = 9;
};

// Decoding refuses a mesh whose arrays would take more than this (a damaged header must not
// make the decoder allocate without bound).
struct DecodeLimits {
  size_t max_mesh_bytes = size_t(1) << 30;
};

// Encodes `mesh` (layout in docs/lod.md). Colours are kept exactly. Throws Error for
// parameters out of range. REQUIRES: validate(mesh) passes.
std::vector<uint8_t> encode_mesh(const Mesh& mesh, const CodecParams& params = {});

// Decodes what encode_mesh wrote. Any damaged or truncated input gives Error naming `where`
// and the field, never a crash; a damage the codecs cannot detect gives a valid mesh
// (validate() passes) with wrong geometry.
Mesh decode_mesh(std::span<const uint8_t> bytes, std::string_view where,
                 const DecodeLimits& limits = {});

// The same mesh as encode_mesh writes it without zstd: the zstd layer removed, every other byte
// as it was (a browser decodes meshoptimizer's codecs but has no zstd). Bytes without the zstd
// flag come back unchanged. Throws Error as decode_mesh does for a damaged header or frame.
std::vector<uint8_t> without_zstd(std::span<const uint8_t> bytes, std::string_view where,
                                  const DecodeLimits& limits = {});

}  // namespace cellwalk
