// Seed 004 (Zheng), §4.1 and §5.3 over TCP: the VDR streaming messages (docs/protocol.md,
// "VDR streaming").
#include "cellwalk/systems/vdr/vdr_protocol.hpp"

#include <cmath>
#include <numbers>

#include "core/bytes.hpp"
#include "net/message_parse.hpp"

namespace cellwalk::vdr {
namespace {

using net::expect_end;
using net::parsing;
using net::ProtocolError;

constexpr uint8_t kLockstepFlag = 1;

void put_vec(ByteWriter& w, const Vec3& v) {
  w.put(v.x);
  w.put(v.y);
  w.put(v.z);
}

Vec3 get_vec(ByteReader& r, const char* what) {
  Vec3 v;
  v.x = r.get<float>(what);
  v.y = r.get<float>(what);
  v.z = r.get<float>(what);
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
    throw ProtocolError(std::string(what) + " is not a finite vector");
  return v;
}

std::vector<Vec3> get_vecs(ByteReader& r, uint32_t n, const char* what) {
  if (uint64_t(n) * 12 > r.remaining()) throw ProtocolError(std::string(what) + ": the message is too short for " + std::to_string(n));
  std::vector<Vec3> out(n);
  for (Vec3& v : out) v = get_vec(r, what);
  return out;
}

}  // namespace

std::vector<uint8_t> encode_hello(const Hello& h) {
  ByteWriter w;
  w.put(kVdrProtocolVersion);
  w.put(uint8_t(h.kind));
  w.put(uint8_t(h.units));
  w.put(uint8_t(h.lockstep ? kLockstepFlag : 0));
  w.put(uint8_t(0));
  return std::move(w.bytes());
}

Hello parse_hello(std::span<const uint8_t> payload) {
  return parsing("hello", [&] {
    ByteReader r(payload, "hello");
    const uint32_t version = r.get<uint32_t>("version");
    if (version != kVdrProtocolVersion)
      throw ProtocolError("VDR protocol version " + std::to_string(version) + ", this server speaks " + std::to_string(kVdrProtocolVersion));
    const uint8_t kind = r.get<uint8_t>("traversal"), units = r.get<uint8_t>("units"), flags = r.get<uint8_t>("flags");
    const uint8_t reserved = r.get<uint8_t>("reserved");
    expect_end(r, "hello");
    if (kind > uint8_t(TraversalKind::kConstant)) throw ProtocolError("traversal " + std::to_string(kind) + " is not 0, 1 or 2");
    if (units > uint8_t(ErrorUnits::kLength)) throw ProtocolError("error units " + std::to_string(units) + " are not 0 or 1");
    if ((flags & ~kLockstepFlag) != 0 || reserved != 0) throw ProtocolError("unknown hello flags");
    return Hello{TraversalKind(kind), ErrorUnits(units), (flags & kLockstepFlag) != 0};
  });
}

std::vector<uint8_t> encode_welcome(const VdrWelcome& x) {
  ByteWriter w;
  w.put(x.vsplits);
  put_vec(w, x.bounds.min);
  put_vec(w, x.bounds.max);
  w.put(uint32_t(x.positions.size()));
  w.put(uint32_t(x.indices.size() / 3));
  for (const Vec3& p : x.positions) put_vec(w, p);
  for (const Vec3& n : x.normals) put_vec(w, n);
  w.put_array(std::span<const uint32_t>(x.indices));
  return std::move(w.bytes());
}

VdrWelcome parse_welcome(std::span<const uint8_t> payload) {
  return parsing("welcome", [&] {
    ByteReader r(payload, "welcome");
    VdrWelcome x;
    x.vsplits = r.get<uint32_t>("vsplits");
    x.bounds.min = get_vec(r, "bounds");
    x.bounds.max = get_vec(r, "bounds");
    const uint32_t vertices = r.get<uint32_t>("vertices"), triangles = r.get<uint32_t>("triangles");
    if (x.bounds.empty() || vertices == 0 || triangles == 0) throw ProtocolError("a welcome with an empty base mesh");
    x.positions = get_vecs(r, vertices, "positions");
    x.normals = get_vecs(r, vertices, "normals");
    x.indices = r.get_array<uint32_t>(uint64_t(triangles) * 3, "indices");
    expect_end(r, "welcome");
    for (uint32_t i : x.indices)
      if (i >= vertices) throw ProtocolError("a base triangle names vertex " + std::to_string(i) + " of " + std::to_string(vertices));
    return x;
  });
}

std::vector<uint8_t> encode_view(const ViewRequest& v) {
  ByteWriter w;
  w.put(v.sequence);
  put_vec(w, v.view.eye);
  put_vec(w, v.view.aim);
  w.put(v.view.alpha);
  w.put(v.view.tau);
  w.put(uint8_t(v.view.mode));
  w.put(uint16_t(v.view.n));
  w.put(v.view.budget);
  w.put(v.applied);
  w.put(v.digest);
  return std::move(w.bytes());
}

ViewRequest parse_view(std::span<const uint8_t> payload) {
  return parsing("view", [&] {
    ByteReader r(payload, "view");
    ViewRequest v;
    v.sequence = r.get<uint32_t>("sequence");
    v.view.eye = get_vec(r, "eye");
    v.view.aim = get_vec(r, "aim");
    v.view.alpha = r.get<float>("alpha");
    v.view.tau = r.get<float>("tau");
    const uint8_t mode = r.get<uint8_t>("mode");
    v.view.n = r.get<uint16_t>("N");
    v.view.budget = r.get<uint32_t>("budget");
    v.applied = r.get<uint32_t>("applied");
    v.digest = r.get<uint64_t>("digest");
    expect_end(r, "view");
    if (v.view.eye == v.view.aim) throw ProtocolError("a view whose eye is its aim point");
    if (!(v.view.alpha > 0 && v.view.alpha < std::numbers::pi_v<float>)) throw ProtocolError("a view cone's half-angle outside (0, π)");
    if (!(v.view.tau > 0 && v.view.tau <= 1)) throw ProtocolError("a tolerance τ outside (0, 1]");
    if (mode > uint8_t(BudgetMode::kBudget)) throw ProtocolError("mode " + std::to_string(mode) + " is neither FREE (0) nor BUDGET (1)");
    if (v.view.n == 0) throw ProtocolError("N = 0: a view that asks for nothing");
    v.view.mode = BudgetMode(mode);
    return v;
  });
}

WireOp wire_op(const ProgressiveMesh& pm, const Op& op) {
  WireOp w;
  w.node = op.node;
  w.split = op.split;
  w.v_p = pm.v_p[op.node];
  if (op.split) {
    w.v_l = pm.v_l[op.node];
    w.v_r = pm.v_r[op.node];
    w.position = pm.positions[pm.v_c(op.node)];
    w.normal = pm.normals[pm.v_c(op.node)];
  }
  const auto adjusted = pm.adjusted_of(op.node);
  w.adjusted.assign(adjusted.begin(), adjusted.end());
  return w;
}

// The layout op_wire_bytes counts: kind, node, v_p, [v_l, v_r, position, normal], count, ids.
std::vector<uint8_t> encode_batch(uint32_t sequence, uint32_t triangles, std::span<const WireOp> ops) {
  ByteWriter w;
  w.put(sequence);
  w.put(triangles);
  w.put(uint32_t(ops.size()));
  for (const WireOp& op : ops) {
    if (op.adjusted.size() > 0xFFFF) fail("vsplit " + std::to_string(op.node), "more than 65,535 adjusted triangles");
    w.put(uint8_t(op.split ? 1 : 0));
    w.put(op.node);
    w.put(op.v_p);
    if (op.split) {
      w.put(op.v_l);
      w.put(op.v_r);
      put_vec(w, op.position);
      put_vec(w, op.normal);
    }
    w.put(uint16_t(op.adjusted.size()));
    w.put_array(std::span<const uint32_t>(op.adjusted));
  }
  return std::move(w.bytes());
}

Batch parse_batch(std::span<const uint8_t> payload, uint32_t vsplits) {
  return parsing("batch", [&] {
    if (payload.size() > kMaxBatchBytes) throw ProtocolError("a batch of " + std::to_string(payload.size()) + " bytes, more than 64 KB");
    ByteReader r(payload, "batch");
    Batch b;
    b.sequence = r.get<uint32_t>("sequence");
    b.triangles = r.get<uint32_t>("triangles");
    const uint32_t n = r.get<uint32_t>("ops");
    if (uint64_t(n) * 11 > r.remaining()) throw ProtocolError("a batch too short for its " + std::to_string(n) + " ops");
    b.ops.resize(n);
    for (WireOp& op : b.ops) {
      const uint8_t kind = r.get<uint8_t>("op kind");
      if (kind > 1) throw ProtocolError("op kind " + std::to_string(kind) + " is neither ecol (0) nor vsplit (1)");
      op.split = kind == 1;
      op.node = r.get<uint32_t>("node");
      if (op.node >= vsplits) throw ProtocolError("node " + std::to_string(op.node) + " of a model with " + std::to_string(vsplits));
      op.v_p = r.get<uint32_t>("v_p");
      if (op.split) {
        op.v_l = r.get<uint32_t>("v_l");
        op.v_r = r.get<uint32_t>("v_r");
        op.position = get_vec(r, "position");
        op.normal = get_vec(r, "normal");
      }
      op.adjusted = r.get_array<uint32_t>(r.get<uint16_t>("adjusted"), "adjusted");
    }
    expect_end(r, "batch");
    return b;
  });
}

std::vector<uint8_t> encode_error(const std::string& reason) {
  ByteWriter w;
  w.put_string(reason.substr(0, 1024));
  return std::move(w.bytes());
}

std::string parse_error(std::span<const uint8_t> payload) {
  return parsing("error", [&] {
    ByteReader r(payload, "error");
    std::string s = r.get_string("reason");
    expect_end(r, "error");
    return s;
  });
}

}  // namespace cellwalk::vdr
