// The VDR streaming protocol (seed 004, §4.1 and §5.3: a base mesh, then one view-parameter
// request and one batch of ecols and vsplits per frame, over one ordered TCP stream;
// docs/protocol.md, "VDR streaming"). Every parser checks counts against the bytes left and ids
// against the model before allocating, and throws net::ProtocolError.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/systems/vdr/progressive_mesh.hpp"
#include "cellwalk/systems/vdr/traversal.hpp"

namespace cellwalk::vdr {

enum class VdrMessage : uint8_t { hello = 16, welcome = 17, view = 18, batch = 19, error = 20 };
constexpr uint32_t kVdrProtocolVersion = 1;
// A batch's payload, header included, never passes this (§4.1's 64 KB).
constexpr uint32_t kMaxBatchBytes = 64 * 1024;
constexpr uint32_t kBatchHeaderBytes = 12;
constexpr uint32_t kNoBatch = 0xFFFFFFFFu;

// Client → server, once. kind / units: the traversal this session runs.
struct Hello {
  TraversalKind kind = TraversalKind::kPriority;
  ErrorUnits units = ErrorUnits::kThesis;
  bool lockstep = false;  // the server keeps a shadow mesh and checks the client's digests
};

// Server → client, once: the base mesh M_0 and what the client needs to check batches.
struct VdrWelcome {
  uint32_t vsplits = 0;  // nodes of the DAG: every node id is below
  Aabb bounds;
  std::vector<Vec3> positions, normals;  // the base vertices
  std::vector<uint32_t> indices;          // three per base triangle
};

// Client → server, each frame it asks for (§5.3 "request"): the view the batch is for (with B
// when the server holds the budget) and, with lockstep, the digest of the client's mesh after
// the last batch it applied. 55 bytes.
struct ViewRequest {
  uint32_t sequence = 0;  // 0, 1, 2, … with no gap: batch k answers request k
  ViewParams view;
  uint32_t applied = kNoBatch;  // the last batch applied, kNoBatch before the first
  uint64_t digest = 0;          // mesh_digest after it (lockstep only)
};

// One op as it travels: a vsplit carries v_c's position and normal and the pivots; an ecol only
// v_p (f_l, f_r and v_c follow from the node id). Both carry the adjusted triangles.
struct WireOp {
  uint32_t node = 0;
  bool split = false;
  uint32_t v_p = 0, v_l = kNone, v_r = kNone;
  Vec3 position{0.0f}, normal{0.0f};
  std::vector<uint32_t> adjusted;
};

// Server → client, one per request, in order: ecols first, then vsplits (§4.3).
struct Batch {
  uint32_t sequence = 0;
  uint32_t triangles = 0;  // the server's cut after the batch: the client's mesh must match
  std::vector<WireOp> ops;
};

std::vector<uint8_t> encode_hello(const Hello& h);
Hello parse_hello(std::span<const uint8_t> payload);
std::vector<uint8_t> encode_welcome(const VdrWelcome& w);
// Checks every index against the vertices and every number for being finite.
VdrWelcome parse_welcome(std::span<const uint8_t> payload);
std::vector<uint8_t> encode_view(const ViewRequest& v);
// Checks the view: finite, eye ≠ aim, 0 < α < π, 0 < τ ≤ 1, 1 ≤ N ≤ 65,535, a known mode.
ViewRequest parse_view(std::span<const uint8_t> payload);
// The op as the model has it, for the encoder.
WireOp wire_op(const ProgressiveMesh& pm, const Op& op);
std::vector<uint8_t> encode_batch(uint32_t sequence, uint32_t triangles, std::span<const WireOp> ops);
// Node ids are checked against `vsplits`; the rest is checked when the op is applied.
Batch parse_batch(std::span<const uint8_t> payload, uint32_t vsplits);
std::vector<uint8_t> encode_error(const std::string& reason);
std::string parse_error(std::span<const uint8_t> payload);

}  // namespace cellwalk::vdr
