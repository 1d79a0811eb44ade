// The mesh codec of the world store: quantisation, octahedral normals, meshoptimizer's
// vertex and index codecs, optional zstd. Layout in docs/lod.md ("Mesh codec").
// Seed: DESIGN.md world store (000 HDoV thesis §4, 001 vLOD §2.4 keep per-object geometry on
// disk). Meyer et al. On floating-point normal vectors. 2010 (octahedral encoding).
#include "cellwalk/store/mesh_codec.hpp"

#include <meshoptimizer.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <string>

#include "core/bytes.hpp"

namespace cellwalk {
namespace {

constexpr std::array<uint8_t, 4> kMagic = {'C', 'W', 'M', 'C'};
constexpr uint8_t kVersion = 1;
constexpr uint8_t kHasNormals = 1, kHasColors = 2, kZstd = 4, kHasUvs = 8, kHasTexture = 16;

// A quantised position; the pad keeps the vertex a multiple of 4 bytes as the codec needs.
struct QuantisedPosition {
  uint16_t x, y, z, pad;
};

struct Header {
  uint8_t flags = 0;
  uint8_t position_bits = 0;
  uint8_t normal_bits = 0;
  uint32_t vertex_count = 0;
  uint32_t index_count = 0;
  Aabb box;
  uint32_t texture = kNoTexture;
};

size_t normal_size(int bits) {
  return bits <= 8 ? 4 : 8;
}
float quantisation_steps(int bits) {
  return float((1u << bits) - 1);
}

// --- encoding --------------------------------------------------------------------------------

std::vector<QuantisedPosition> quantise_positions(const Mesh& mesh, const Aabb& box, int bits) {
  const Vec3 extent = box.size();
  const float steps = quantisation_steps(bits);
  // A flat axis (extent 0) quantises to 0.
  const Vec3 scale = glm::mix(Vec3(0.0f), Vec3(steps) / extent, glm::greaterThan(extent, Vec3(0)));
  std::vector<QuantisedPosition> q(mesh.vertex_count());
  for (size_t i = 0; i < q.size(); ++i) {
    const Vec3 r = glm::clamp(glm::round((mesh.positions[i] - box.min) * scale), 0.0f, steps);
    q[i] = {uint16_t(r.x), uint16_t(r.y), uint16_t(r.z), 0};
  }
  return q;
}

std::vector<uint8_t> octahedral_normals(const Mesh& mesh, int bits) {
  std::vector<float> xyzw(mesh.vertex_count() * 4, 0.0f);
  for (size_t i = 0; i < mesh.vertex_count(); ++i) {
    std::copy_n(&mesh.normals[i].x, 3, &xyzw[i * 4]);
  }
  const size_t stride = normal_size(bits);
  std::vector<uint8_t> out(mesh.vertex_count() * stride);
  meshopt_encodeFilterOct(out.data(), mesh.vertex_count(), stride, bits, xyzw.data());
  return out;
}

void put_vertex_stream(ByteWriter& w, const void* data, size_t count, size_t size) {
  std::vector<uint8_t> buf(meshopt_encodeVertexBufferBound(count, size));
  buf.resize(meshopt_encodeVertexBuffer(buf.data(), buf.size(), data, count, size));
  w.put(uint32_t(buf.size()));
  w.put_array<uint8_t>(buf);
}

void put_index_stream(ByteWriter& w, const Mesh& mesh) {
  std::vector<uint8_t> buf(
      meshopt_encodeIndexBufferBound(mesh.indices.size(), mesh.vertex_count()));
  buf.resize(
      meshopt_encodeIndexBuffer(buf.data(), buf.size(), mesh.indices.data(), mesh.indices.size()));
  w.put(uint32_t(buf.size()));
  w.put_array<uint8_t>(buf);
}

std::vector<uint8_t> encode_body(const Mesh& mesh, const Aabb& box, const CodecParams& p) {
  ByteWriter w;
  const std::vector<QuantisedPosition> q = quantise_positions(mesh, box, p.position_bits);
  put_vertex_stream(w, q.data(), q.size(), sizeof(QuantisedPosition));
  if (!mesh.normals.empty()) {
    const std::vector<uint8_t> n = octahedral_normals(mesh, p.normal_bits);
    put_vertex_stream(w, n.data(), mesh.vertex_count(), normal_size(p.normal_bits));
  }
  if (!mesh.colors.empty()) {
    put_vertex_stream(w, mesh.colors.data(), mesh.vertex_count(), sizeof(Rgba8));
  }
  // Texture coordinates are kept exactly: a texel is small next to a quantisation step.
  if (!mesh.uvs.empty()) put_vertex_stream(w, mesh.uvs.data(), mesh.vertex_count(), sizeof(Vec2));
  put_index_stream(w, mesh);
  return std::move(w.bytes());
}

std::vector<uint8_t> zstd_compress(const std::vector<uint8_t>& raw, int level) {
  std::vector<uint8_t> out(ZSTD_compressBound(raw.size()));
  const size_t n = ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), level);
  if (ZSTD_isError(n)) fail("encode_mesh", std::string("zstd: ") + ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

void check_params(const CodecParams& p) {
  if (p.position_bits < 1 || p.position_bits > 16) {
    fail("encode_mesh", "position_bits must be 1..16, not " + std::to_string(p.position_bits));
  }
  if (p.normal_bits < 2 || p.normal_bits > 16) {
    fail("encode_mesh", "normal_bits must be 2..16, not " + std::to_string(p.normal_bits));
  }
}

// --- decoding --------------------------------------------------------------------------------

Header read_header(ByteReader& r) {
  for (uint8_t m : kMagic) {
    if (r.get<uint8_t>("magic") != m) r.error("not an encoded mesh (bad magic)");
  }
  if (r.get<uint8_t>("version") != kVersion) r.error("unsupported mesh codec version");
  Header h;
  h.flags = r.get<uint8_t>("flags");
  h.position_bits = r.get<uint8_t>("position bits");
  h.normal_bits = r.get<uint8_t>("normal bits");
  h.vertex_count = r.get<uint32_t>("vertex count");
  h.index_count = r.get<uint32_t>("index count");
  h.box.min = r.get<Vec3>("box min");
  h.box.max = r.get<Vec3>("box max");
  if (h.flags & ~(kHasNormals | kHasColors | kZstd | kHasUvs | kHasTexture)) r.error("unknown flags");
  if (h.flags & kHasTexture) {
    if (!(h.flags & kHasUvs)) r.error("a texture without texture coordinates");
    h.texture = r.get<uint32_t>("texture");
    if (h.texture == kNoTexture) r.error("texture flag set but no texture named");
  }
  if (h.position_bits < 1 || h.position_bits > 16) r.error("position bits out of range");
  if (h.normal_bits < 2 || h.normal_bits > 16) r.error("normal bits out of range");
  if (h.index_count % 3 != 0) r.error("index count is not a multiple of 3");
  // A damaged box gives a negative, NaN or infinite extent.
  const Vec3 extent = h.box.size();
  if (h.vertex_count > 0 && !(glm::all(glm::lessThanEqual(Vec3(0), extent)) &&
                              glm::all(glm::lessThan(extent, Vec3(FLT_MAX))))) {
    r.error("bad bounding box");
  }
  return h;
}

size_t mesh_bytes(const Header& h) {
  size_t per_vertex = sizeof(Vec3);
  if (h.flags & kHasNormals) per_vertex += sizeof(Vec3);
  if (h.flags & kHasColors) per_vertex += sizeof(Rgba8);
  if (h.flags & kHasUvs) per_vertex += sizeof(Vec2);
  return size_t(h.vertex_count) * per_vertex + size_t(h.index_count) * sizeof(uint32_t);
}

// The most bytes an honest body for these counts can take, to bound zstd's output.
size_t body_bound(const Header& h) {
  size_t n = 4 + meshopt_encodeVertexBufferBound(h.vertex_count, sizeof(QuantisedPosition));
  if (h.flags & kHasNormals) {
    n += 4 + meshopt_encodeVertexBufferBound(h.vertex_count, normal_size(h.normal_bits));
  }
  if (h.flags & kHasColors) n += 4 + meshopt_encodeVertexBufferBound(h.vertex_count, 4);
  if (h.flags & kHasUvs) n += 4 + meshopt_encodeVertexBufferBound(h.vertex_count, sizeof(Vec2));
  return n + 4 + meshopt_encodeIndexBufferBound(h.index_count, h.vertex_count);
}

std::vector<uint8_t> zstd_body(ByteReader& r, const Header& h) {
  const uint32_t raw_size = r.get<uint32_t>("zstd raw size");
  if (raw_size > body_bound(h)) r.error("zstd raw size too large for the mesh's counts");
  // An empty frame is damage; checked here because get_array must not copy 0 bytes from null.
  if (r.remaining() == 0) r.error("missing zstd frame");
  const std::vector<uint8_t> frame = r.get_array<uint8_t>(r.remaining(), "zstd frame");
  std::vector<uint8_t> raw(raw_size);
  const size_t n = ZSTD_decompress(raw.data(), raw.size(), frame.data(), frame.size());
  if (ZSTD_isError(n)) r.error(std::string("zstd: ") + ZSTD_getErrorName(n));
  if (n != raw_size) r.error("zstd frame shorter than its declared size");
  return raw;
}

// One length-prefixed codec stream. meshopt's codecs never write an empty one, so an empty
// one is damage (and get_array must not copy 0 bytes from null).
std::vector<uint8_t> get_stream(ByteReader& r, std::string_view what) {
  const uint32_t length = r.get<uint32_t>(what);
  if (length == 0) r.error("empty " + std::string(what) + " stream");
  return r.get_array<uint8_t>(length, what);
}

// Decodes one vertex stream into `count` records of `size` bytes.
void get_vertex_stream(ByteReader& r, void* out, size_t count, size_t size, std::string_view what) {
  const std::vector<uint8_t> enc = get_stream(r, what);
  if (meshopt_decodeVertexBuffer(out, count, size, enc.data(), enc.size()) != 0) {
    r.error(std::string("damaged ") + std::string(what));
  }
}

void get_positions(ByteReader& r, const Header& h, Mesh& mesh) {
  std::vector<QuantisedPosition> q(h.vertex_count);
  get_vertex_stream(r, q.data(), q.size(), sizeof(QuantisedPosition), "positions");
  const float steps = quantisation_steps(h.position_bits);
  const Vec3 step = h.box.size() / steps;
  mesh.positions.resize(h.vertex_count);
  for (size_t i = 0; i < q.size(); ++i) {
    // Values above 2^bits - 1 only come from damage; clamping keeps positions in the box.
    const Vec3 v = glm::min(Vec3(q[i].x, q[i].y, q[i].z), Vec3(steps));
    // The top step is the box's max exactly (min + steps · step may round past or short of
    // it): faces of two objects that meet where both boxes end then meet without a gap.
    mesh.positions[i] = glm::mix(h.box.min + v * step, h.box.max, glm::equal(v, Vec3(steps)));
  }
}

// Octahedral decode done here rather than with meshopt_decodeFilterOct, which trusts the
// stored z to hold 1.0 and divides by a length that damaged data can make 0.
template <typename T>
void decode_octahedral(const T* packed, int bits, std::vector<Vec3>& out) {
  const float max = float((1 << (bits - 1)) - 1);
  for (size_t i = 0; i < out.size(); ++i) {
    float x = std::clamp(packed[i * 4] / max, -1.0f, 1.0f);
    float y = std::clamp(packed[i * 4 + 1] / max, -1.0f, 1.0f);
    const float z = 1.0f - std::abs(x) - std::abs(y);
    const float t = std::max(-z, 0.0f);  // fold the lower hemisphere back
    x += x >= 0.0f ? -t : t;
    y += y >= 0.0f ? -t : t;
    // |x| + |y| + |z| = 1 here, so the length is at least 1/sqrt(3).
    out[i] = glm::normalize(Vec3(x, y, z));
  }
}

void get_normals(ByteReader& r, const Header& h, Mesh& mesh) {
  const size_t size = normal_size(h.normal_bits);
  std::vector<uint8_t> packed(size_t(h.vertex_count) * size);
  get_vertex_stream(r, packed.data(), h.vertex_count, size, "normals");
  mesh.normals.resize(h.vertex_count);
  if (size == 4) {
    decode_octahedral(reinterpret_cast<const int8_t*>(packed.data()), h.normal_bits, mesh.normals);
  } else {
    std::vector<int16_t> wide(packed.size() / 2);
    std::memcpy(wide.data(), packed.data(), packed.size());
    decode_octahedral(wide.data(), h.normal_bits, mesh.normals);
  }
}

void get_indices(ByteReader& r, const Header& h, Mesh& mesh) {
  const std::vector<uint8_t> enc = get_stream(r, "indices");
  mesh.indices.resize(h.index_count);
  if (meshopt_decodeIndexBuffer(mesh.indices.data(), mesh.indices.size(), sizeof(uint32_t),
                                enc.data(), enc.size()) != 0) {
    r.error("damaged indices");
  }
  // The index codec is safe on any input but can produce any index.
  for (uint32_t i : mesh.indices) {
    if (i >= h.vertex_count) r.error("index out of range");
  }
}

Mesh decode_body(ByteReader& r, const Header& h) {
  Mesh mesh;
  get_positions(r, h, mesh);
  if (h.flags & kHasNormals) get_normals(r, h, mesh);
  if (h.flags & kHasColors) {
    mesh.colors.resize(h.vertex_count);
    get_vertex_stream(r, mesh.colors.data(), h.vertex_count, sizeof(Rgba8), "colors");
  }
  if (h.flags & kHasUvs) {
    mesh.uvs.resize(h.vertex_count);
    get_vertex_stream(r, mesh.uvs.data(), h.vertex_count, sizeof(Vec2), "texture coordinates");
  }
  mesh.texture = h.texture;
  get_indices(r, h, mesh);
  if (r.remaining() != 0) r.error("trailing bytes after the index stream");
  return mesh;
}

}  // namespace

std::vector<uint8_t> encode_mesh(const Mesh& mesh, const CodecParams& params) {
  check_params(params);
  const Aabb box = mesh.vertex_count() > 0 ? bounds_of(mesh) : Aabb{Vec3(0), Vec3(0)};
  ByteWriter w;
  w.put_array<uint8_t>(kMagic);
  w.put(kVersion);
  w.put(uint8_t((mesh.normals.empty() ? 0 : kHasNormals) | (mesh.colors.empty() ? 0 : kHasColors) |
                (params.zstd ? kZstd : 0) | (mesh.uvs.empty() ? 0 : kHasUvs) |
                (mesh.texture == kNoTexture ? 0 : kHasTexture)));
  w.put(uint8_t(params.position_bits));
  w.put(uint8_t(params.normal_bits));
  w.put(uint32_t(mesh.vertex_count()));
  w.put(uint32_t(mesh.indices.size()));
  w.put(box.min);
  w.put(box.max);
  if (mesh.texture != kNoTexture) w.put(mesh.texture);
  std::vector<uint8_t> body = encode_body(mesh, box, params);
  if (params.zstd) {
    w.put(uint32_t(body.size()));
    body = zstd_compress(body, params.zstd_level);
  }
  w.put_array<uint8_t>(body);
  return std::move(w.bytes());
}

Mesh decode_mesh(std::span<const uint8_t> bytes, std::string_view where,
                 const DecodeLimits& limits) {
  ByteReader r(bytes, std::string(where));
  const Header h = read_header(r);
  if (mesh_bytes(h) > limits.max_mesh_bytes) r.error("mesh larger than the decode limit");
  Mesh mesh;
  if (h.flags & kZstd) {
    const std::vector<uint8_t> raw = zstd_body(r, h);
    ByteReader body(raw, std::string(where) + " (zstd body)");
    mesh = decode_body(body, h);
  } else {
    mesh = decode_body(r, h);
  }
  validate(mesh, where);  // the guarantee decode_mesh gives, checked rather than assumed
  return mesh;
}

std::vector<uint8_t> without_zstd(std::span<const uint8_t> bytes, std::string_view where,
                                  const DecodeLimits& limits) {
  ByteReader r(bytes, std::string(where));
  const Header h = read_header(r);
  if (!(h.flags & kZstd)) return {bytes.begin(), bytes.end()};
  if (mesh_bytes(h) > limits.max_mesh_bytes) r.error("mesh larger than the decode limit");
  const size_t header_bytes = bytes.size() - r.remaining();
  const std::vector<uint8_t> raw = zstd_body(r, h);
  std::vector<uint8_t> out(bytes.begin(), bytes.begin() + ptrdiff_t(header_bytes));
  constexpr size_t kFlagsOffset = kMagic.size() + 1;  // after the magic and the version
  out[kFlagsOffset] = uint8_t(out[kFlagsOffset] & ~kZstd);
  out.insert(out.end(), raw.begin(), raw.end());
  return out;
}

}  // namespace cellwalk
