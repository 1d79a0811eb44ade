// Stratified thesis §3.1.2, §5.2.3 (digest 002 §4, "[ours] Proposal"): the stored near lists and
// far faces. Layout: docs/format.md, "`stratified` and `farfield`".
#include "cellwalk/systems/stratified/stored_stratified.hpp"

#include <zstd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>

#include "cellwalk/core/error.hpp"
#include "cellwalk/visibility/id_codec.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "core/bytes.hpp"

namespace cellwalk::stratified {
namespace {

constexpr uint32_t kVersion = 2;  // 2: depth as 8-bit disparity
constexpr int kZstdLevel = 6;

std::vector<uint8_t> compress(std::span<const uint8_t> raw) {
  std::vector<uint8_t> frame(ZSTD_compressBound(raw.size()));
  const size_t n = ZSTD_compress(frame.data(), frame.size(), raw.data(), raw.size(), kZstdLevel);
  if (ZSTD_isError(n)) fail("stratify (zstd)", ZSTD_getErrorName(n));
  frame.resize(n);
  return frame;
}

void check_frame_size(std::span<const uint8_t> frame, uint64_t bytes, ByteReader& r, const char* what) {
  if (ZSTD_getFrameContentSize(frame.data(), frame.size()) != bytes)
    r.error(std::string(what) + ": the zstd frame does not hold one face's texels");
}

// REQUIRES: `out` has the size the frame must decode to.
void decompress(std::span<const uint8_t> frame, std::span<uint8_t> out, ByteReader& r, const char* what) {
  check_frame_size(frame, out.size(), r, what);
  const size_t n = ZSTD_decompress(out.data(), out.size(), frame.data(), frame.size());
  if (ZSTD_isError(n) || n != out.size()) r.error(std::string(what) + ": damaged zstd frame");
}

template <typename T>
std::span<const uint8_t> as_bytes(const std::vector<T>& v) {
  return {reinterpret_cast<const uint8_t*>(v.data()), v.size() * sizeof(T)};
}
template <typename T>
std::span<uint8_t> as_writable_bytes(std::vector<T>& v) {
  return {reinterpret_cast<uint8_t*>(v.data()), v.size() * sizeof(T)};
}

// Depth as 8 bits of disparity s = (b/2)/d (s <= 1 for far texels, which lie outside the box):
// q = 1 + floor(254·s), clamped to [1, 255]; 0 = nothing there. Decoding gives the farthest
// distance the byte allows, (b/2)·254/(q − 1), infinite for q = 1. Why disparity: the far
// field's angular error grows like 1/(face distance) − 1/d, so equal steps of s are nearly equal
// steps of error (about α/254 each, more as the eye nears the face). Why the farthest: the error
// seen from any eye grows with d beyond the face, so the measured angle is an upper bound.
std::vector<uint8_t> quantise_depth(const std::vector<float>& depth, float b) {
  std::vector<uint8_t> q(depth.size(), 0);
  for (size_t i = 0; i < depth.size(); ++i)
    if (depth[i] > 0) q[i] = uint8_t(1 + std::min(254.0, std::floor(254.0 * 0.5 * b / depth[i])));
  return q;
}

std::vector<float> dequantise_depth(const std::vector<uint8_t>& q, float b) {
  std::vector<float> depth(q.size(), 0.0f);
  for (size_t i = 0; i < q.size(); ++i)
    if (q[i] == 1) depth[i] = std::numeric_limits<float>::infinity();
    else if (q[i] > 1) depth[i] = float(0.5 * b * 254.0 / (q[i] - 1));
  return depth;
}

// The quantised depth as zstd sees it: each texel's difference from its left neighbour (mod 256;
// surfaces are smooth, so differences are mostly 0 or ±1).
std::vector<uint8_t> depth_deltas(const std::vector<uint8_t>& q, int resolution) {
  std::vector<uint8_t> d(q.size());
  for (size_t i = 0; i < q.size(); ++i) d[i] = uint8_t(q[i] - (i % resolution ? q[i - 1] : 0));
  return d;
}

std::vector<uint8_t> depth_from_deltas(std::vector<uint8_t> d, int resolution) {
  for (size_t i = 0; i < d.size(); ++i)
    if (i % resolution) d[i] = uint8_t(d[i] + d[i - 1]);
  return d;
}

}  // namespace

std::vector<uint8_t> encode_far_field(const CellFarField& field, float b, StratifiedSizes& sizes) {
  ByteWriter w;
  uint32_t mask = 0;
  for (const FaceImage& f : field.faces) mask |= 1u << f.face;
  w.put(mask);
  for (const FaceImage& f : field.faces) {
    const std::vector<uint8_t> color = compress(f.color.rgba);
    const std::vector<uint8_t> ids = compress(as_bytes(f.ids.ids));
    const std::vector<uint8_t> depth = compress(depth_deltas(quantise_depth(f.depth, b), f.color.width));
    w.put(uint32_t(color.size()));
    w.put(uint32_t(ids.size()));
    w.put(uint32_t(depth.size()));
    w.put_array<uint8_t>(color);
    w.put_array<uint8_t>(ids);
    w.put_array<uint8_t>(depth);
    sizes.faces += 1;
    sizes.raw_face_bytes += uint64_t(f.color.width) * f.color.height * (4 + 4 + 1);
    sizes.color_bytes += color.size();
    sizes.id_bytes += ids.size();
    sizes.depth_bytes += depth.size();
  }
  return std::move(w.bytes());
}

void count_far_record(std::span<const uint8_t> record, int resolution, StratifiedSizes& sizes) {
  ByteReader r(record, "far-field record");
  const uint32_t mask = r.get<uint32_t>("face mask");
  for (int face = 0; face < kFaceCount; ++face) {
    if (!(mask >> face & 1)) continue;
    const uint32_t color = r.get<uint32_t>("colour bytes"), ids = r.get<uint32_t>("id bytes"), depth = r.get<uint32_t>("depth bytes");
    r.get_array<uint8_t>(uint64_t(color) + ids + depth, "frames");
    sizes.faces += 1;
    sizes.raw_face_bytes += uint64_t(resolution) * resolution * (4 + 4 + 1);
    sizes.color_bytes += color;
    sizes.id_bytes += ids;
    sizes.depth_bytes += depth;
  }
}

CellFarField decode_far_field(std::span<const uint8_t> bytes, float b, int resolution, uint64_t object_count,
                              const std::string& where) {
  ByteReader r(bytes, where);
  const uint32_t mask = r.get<uint32_t>("face mask");
  if (mask >> kFaceCount) r.error("face mask names a face past the sixth");
  const size_t texels = size_t(resolution) * resolution;
  CellFarField field;
  for (int face = 0; face < kFaceCount; ++face) {
    if (!(mask >> face & 1)) continue;
    const uint32_t color_bytes = r.get<uint32_t>("colour bytes"), id_bytes = r.get<uint32_t>("id bytes"),
                   depth_bytes = r.get<uint32_t>("depth bytes");
    const std::vector<uint8_t> color = r.get_array<uint8_t>(color_bytes, "colour frame");
    const std::vector<uint8_t> ids = r.get_array<uint8_t>(id_bytes, "id frame");
    const std::vector<uint8_t> depth_frame = r.get_array<uint8_t>(depth_bytes, "depth frame");
    // Sizes first: a hostile record must not make the decoder allocate what the frames do not hold.
    check_frame_size(color, texels * 4, r, "colour");
    check_frame_size(ids, texels * 4, r, "ids");
    check_frame_size(depth_frame, texels, r, "depth");
    FaceImage f;
    f.face = face;
    f.color = {resolution, resolution, std::vector<uint8_t>(texels * 4)};
    f.ids = {resolution, resolution, std::vector<uint32_t>(texels)};
    std::vector<uint8_t> depth(texels);
    decompress(color, f.color.rgba, r, "colour");
    decompress(ids, as_writable_bytes(f.ids.ids), r, "ids");
    decompress(depth_frame, depth, r, "depth");
    for (const uint32_t id : f.ids.ids)
      if (id > object_count) r.error("a texel names object " + std::to_string(id - 1) + ", past the world's objects");
    f.depth = dequantise_depth(depth_from_deltas(std::move(depth), resolution), b);
    field.faces.push_back(std::move(f));
  }
  if (r.remaining() != 0) r.error("bytes after the last face");
  return field;
}

StratifiedSizes write_world_with_stratified(const World& world, const std::string& out, const Viewcells& cells,
                                            const StratifiedParams& params,
                                            const std::function<std::vector<uint8_t>(CellId)>& bake,
                                            const std::function<void(uint64_t, uint64_t)>& progress) {
  const ViewCellPartition& partition = *cells.partition;
  const size_t n = partition.cell_count();
  StratifiedSizes sizes;
  sizes.cells = n;
  uint64_t to_bake = 0;
  for (CellId c = 0; c < n; ++c) to_bake += partition.cell(c).computed();
  std::vector<uint64_t> far_offsets(n + 1, 0);
  auto write_far = [&](WorldWriter& w) {
    const auto start = std::chrono::steady_clock::now();
    for (CellId c = 0; c < n; ++c) {
      far_offsets[c] = w.section_offset();
      if (!partition.cell(c).computed()) continue;
      const std::vector<uint8_t> record = bake(c);
      count_far_record(record, params.resolution, sizes);
      w.write(record);
      ++sizes.baked_cells;
      if (progress) progress(sizes.baked_cells, to_bake);
    }
    far_offsets[n] = w.section_offset();
    sizes.bake_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  auto write_cells = [&](WorldWriter& w) {
    ByteWriter s;
    s.put(kVersion);
    s.put(params.alpha);
    s.put(params.v);
    s.put(params.b);
    s.put_string(params.sizing);
    s.put(uint32_t(params.resolution));
    s.put(params.far_level_texels);
    s.put(uint64_t(world.object_count()));
    const std::vector<uint8_t> part = serialize_partition(partition);
    s.put(uint64_t(part.size()));
    s.put_array<uint8_t>(part);
    std::vector<uint8_t> near;
    std::vector<uint64_t> near_offsets{0};
    for (CellId c = 0; c < n; ++c) {
      const std::span<const ObjectId> list = cells.near.near(c);
      visibility::encode_ids(visibility::IdCodec::kVarintGaps, list, near);
      near_offsets.push_back(near.size());
      sizes.near_ids += list.size();
    }
    sizes.near_bytes = near.size();
    s.put_array<uint64_t>(near_offsets);
    s.put(uint64_t(near.size()));
    s.put_array<uint8_t>(near);
    s.put_array<uint64_t>(far_offsets);
    w.write(s.bytes());
  };
  visibility::write_world_sections(world, out, {{kFarFieldSection, {}, write_far}, {kStratifiedSection, {}, write_cells}},
                                   {kFarFieldSection, kStratifiedSection});
  return sizes;
}

StoredStratified::StoredStratified(const World& world) : world_(world) {
  const std::string path = world.file().path();
  if (!world.file().has_section(kStratifiedSection) || !world.file().has_section(kFarFieldSection))
    fail(path, "has no stratified preprocessing; run `cellwalk stratify build " + path + "` first");
  const std::vector<uint8_t> bytes = world.file().read_all(kStratifiedSection);
  ByteReader r(bytes, path + " section stratified");
  if (r.get<uint32_t>("version") != kVersion) r.error("unknown stratified version; rebuild with `cellwalk stratify build`");
  params_.alpha = r.get<float>("alpha");
  params_.v = r.get<float>("v");
  params_.b = r.get<float>("b");
  params_.sizing = r.get_string("sizing");
  params_.resolution = int(r.get<uint32_t>("resolution"));
  params_.far_level_texels = r.get<float>("far level texels");
  if (!(params_.v > 0 && params_.b > params_.v && std::isfinite(params_.b)) || !(params_.alpha > 0))
    r.error("sizes are not 0 < v < b with α > 0");
  if (params_.resolution < 1 || params_.resolution > kMaxFaceResolution) r.error("face resolution out of range");
  if (!(params_.far_level_texels >= 0.0f) || !std::isfinite(params_.far_level_texels)) r.error("far level texels not 0 or more");
  if (r.get<uint64_t>("object count") != world.object_count()) r.error("object count differs from the world's");
  const uint64_t part_bytes = r.get<uint64_t>("partition bytes");
  partition_ = deserialize_partition(r.get_array<uint8_t>(part_bytes, "partition"), path + " section stratified (cells)");
  const uint64_t cells = partition_->cell_count();
  near_offsets_ = r.get_array<uint64_t>(cells + 1, "near offsets");
  near_bytes_ = r.get_array<uint8_t>(r.get<uint64_t>("near bytes"), "near lists");
  far_offsets_ = r.get_array<uint64_t>(cells + 1, "far offsets");
  if (r.remaining() != 0) r.error("bytes after the far offsets");
  const uint64_t far_size = world.file().section(kFarFieldSection).bytes;
  for (size_t i = 0; i <= cells; ++i) {
    if (near_offsets_[i] > near_bytes_.size() || (i > 0 && near_offsets_[i] < near_offsets_[i - 1]))
      r.error("bad near-list offsets");
    if (far_offsets_[i] > far_size || (i > 0 && far_offsets_[i] < far_offsets_[i - 1])) r.error("bad far-field offsets");
  }
}

StoredStratified::~StoredStratified() = default;

std::vector<ObjectId> StoredStratified::near(CellId cell) const {
  if (cell >= partition_->cell_count()) fail("stratified", "cell " + std::to_string(cell) + " is past the stored cells");
  size_t pos = near_offsets_[cell];
  const std::string where = world_.file().path() + " section stratified (near lists)";
  std::vector<uint32_t> ids = visibility::decode_ids(visibility::IdCodec::kVarintGaps,
                                                     std::span(near_bytes_).first(near_offsets_[cell + 1]), pos, where,
                                                     world_.object_count());
  if (pos != near_offsets_[cell + 1])
    fail(where + "@" + std::to_string(pos), "bytes after cell " + std::to_string(cell) + "'s near list");
  return {ids.begin(), ids.end()};
}

uint64_t StoredStratified::far_field_bytes(CellId cell) const {
  return far_offsets_.at(cell + 1) - far_offsets_.at(cell);
}

uint64_t StoredStratified::load_bound(CellId cell) const {
  const uint64_t texels = uint64_t(params_.resolution) * params_.resolution;
  const uint64_t near_record = near_offsets_.at(cell + 1) - near_offsets_.at(cell);
  return far_field_bytes(cell) + kFaceCount * texels * (4 + 4 + 4) + near_record * sizeof(ObjectId) + 64;
}

CellFarField StoredStratified::far_field(CellId cell) const {
  if (cell >= partition_->cell_count()) fail("stratified", "cell " + std::to_string(cell) + " is past the stored cells");
  const SectionInfo& section = world_.file().section(kFarFieldSection);
  const std::vector<uint8_t> bytes = world_.file().read(section, far_offsets_[cell], far_field_bytes(cell));
  return decode_far_field(bytes, params_.b, params_.resolution, world_.object_count(),
                          world_.file().path() + " section farfield (cell " + std::to_string(cell) + ")");
}

uint64_t StoredStratified::resident_bytes() const {
  return sizeof(*this) + near_bytes_.capacity() + 8 * (near_offsets_.capacity() + far_offsets_.capacity()) +
         partition_->cell_count() * sizeof(ViewCell) * 3;
}

}  // namespace cellwalk::stratified
