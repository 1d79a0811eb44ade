// The scene file (.cwscene): see docs/format.md, "Scene file".
#include "cellwalk/scene/scene_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "core/bytes.hpp"
#include "scene/scene_info_codec.hpp"

namespace cellwalk {
namespace {

constexpr char kMagic[8] = {'C', 'W', 'S', 'C', 'E', 'N', 'E', '1'};
constexpr char kEndMagic[8] = {'C', 'W', 'S', 'C', 'E', 'N', 'D', '1'};
// Version 2 added texture coordinates, textures and the texture table; 1 is still read.
constexpr uint32_t kVersion = 2;
constexpr size_t kHeaderBytes = 16;
constexpr size_t kFrameBytes = 16;    // u32 payload size, u32 zero, u64 xxh3 of the payload
constexpr size_t kTrailerBytes = 24;  // u64 footer offset, u64 footer bytes, end magic
constexpr size_t kEntryBytes = 44;   // u64 offset, u32 size, u32 triangles, u32 colour, 6 f32 box
constexpr size_t kTextureEntryBytes = 12;  // u64 offset, u32 size
constexpr uint32_t kHasNormals = 1, kHasColors = 2, kHasUvs = 4, kHasTexture = 8;

// Frames a payload: size, zero, checksum, payload.
void write_framed(AtomicFile& file, std::span<const uint8_t> payload) {
  ByteWriter frame;
  frame.put(static_cast<uint32_t>(payload.size()));
  frame.put(uint32_t{0});
  frame.put(static_cast<uint64_t>(XXH3_64bits(payload.data(), payload.size())));
  file.write(frame.bytes());
  file.write(payload);
}

void encode_object(ByteWriter& w, const Object& o) {
  const Mesh& m = o.mesh;
  w.put(o.id);
  w.put(o.color);
  put_box(w, o.bounds);
  w.put_string(o.name);
  w.put(static_cast<uint32_t>(m.positions.size()));
  w.put(static_cast<uint32_t>(m.indices.size()));
  w.put(uint32_t((m.normals.empty() ? 0 : kHasNormals) | (m.colors.empty() ? 0 : kHasColors) |
                 (m.uvs.empty() ? 0 : kHasUvs) | (m.texture == kNoTexture ? 0 : kHasTexture)));
  if (m.texture != kNoTexture) w.put(m.texture);
  w.put_array(std::span<const Vec3>(m.positions));
  w.put_array(std::span<const Vec3>(m.normals));
  w.put_array(std::span<const Rgba8>(m.colors));
  w.put_array(std::span<const Vec2>(m.uvs));
  w.put_array(std::span<const uint32_t>(m.indices));
}

}  // namespace

struct SceneWriter::Impl {
  explicit Impl(std::string path) : file(std::move(path)) {
    ByteWriter header;
    header.put(kMagic);
    header.put(kVersion);
    header.put(uint32_t{0});
    file.write(header.bytes());
  }
  AtomicFile file;
  std::vector<SceneEntry> entries;
  std::vector<std::pair<uint64_t, uint32_t>> textures;
  uint64_t triangles = 0;
  Aabb bounds;
  ByteWriter scratch;
};

SceneWriter::SceneWriter(std::string path) : impl_(std::make_unique<Impl>(std::move(path))) {}
SceneWriter::~SceneWriter() = default;

void SceneWriter::add(const Object& object) {
  if (object.id != impl_->entries.size())
    fail(impl_->file.path(), "object ids must be dense: got " + std::to_string(object.id) +
                                 ", expected " + std::to_string(impl_->entries.size()));
  validate(object.mesh, impl_->file.path() + ": object " + std::to_string(object.id));
  if (object.mesh.texture != kNoTexture && object.mesh.texture >= impl_->textures.size())
    fail(impl_->file.path(), "object " + std::to_string(object.id) + " (" + object.name + ") samples texture " +
                                 std::to_string(object.mesh.texture) + ", but only " +
                                 std::to_string(impl_->textures.size()) + " were added before it");
  ByteWriter& w = impl_->scratch;
  w.clear();
  encode_object(w, object);
  if (w.size() > UINT32_MAX - kFrameBytes)
    fail(impl_->file.path(), "object " + std::to_string(object.id) + " (" + object.name +
                                 ") is larger than 4 GiB, the scene format's limit per object");
  SceneEntry e;
  e.offset = impl_->file.size();
  e.size = static_cast<uint32_t>(kFrameBytes + w.size());
  e.triangles = static_cast<uint32_t>(object.mesh.triangle_count());
  e.color = object.color;
  e.bounds = object.bounds;
  write_framed(impl_->file, w.bytes());
  impl_->entries.push_back(e);
  impl_->triangles += e.triangles;
  impl_->bounds.extend(object.bounds);
}

void SceneWriter::add_texture(const TextureImage& texture) {
  const std::string where = impl_->file.path() + ": texture " + std::to_string(impl_->textures.size()) +
                            " (" + texture.name + ")";
  check_texture(texture.encoded, where);
  ByteWriter& w = impl_->scratch;
  w.clear();
  w.put_string(texture.name);
  w.put(uint64_t(texture.encoded.size()));
  w.put_array(std::span<const uint8_t>(texture.encoded));
  if (w.size() > UINT32_MAX - kFrameBytes) fail(where, "is larger than 4 GiB, the scene format's limit");
  impl_->textures.emplace_back(impl_->file.size(), uint32_t(kFrameBytes + w.size()));
  write_framed(impl_->file, w.bytes());
}

void SceneWriter::finish(SceneInfo info) {
  info.bounds = impl_->bounds;
  ByteWriter w;
  w.put(static_cast<uint32_t>(impl_->entries.size()));
  w.put(impl_->triangles);
  encode_scene_info(w, info);
  for (const SceneEntry& e : impl_->entries) {
    w.put(e.offset);
    w.put(e.size);
    w.put(e.triangles);
    w.put(e.color);
    put_box(w, e.bounds);
  }
  w.put(static_cast<uint32_t>(impl_->textures.size()));
  for (const auto& [offset, size] : impl_->textures) {
    w.put(offset);
    w.put(size);
  }
  const uint64_t footer_offset = impl_->file.size();
  write_framed(impl_->file, w.bytes());
  ByteWriter trailer;
  trailer.put(footer_offset);
  trailer.put(static_cast<uint64_t>(kFrameBytes + w.size()));
  trailer.put(kEndMagic);
  impl_->file.write(trailer.bytes());
  impl_->file.commit();
}

namespace {

// Reads exactly bytes [offset, offset + n) or throws naming the file and offset.
std::vector<uint8_t> pread_exact(int fd, const std::string& path, uint64_t offset, uint64_t n) {
  std::vector<uint8_t> bytes(n);
  uint64_t done = 0;
  while (done < n) {
    ssize_t got = ::pread(fd, bytes.data() + done, n - done, static_cast<off_t>(offset + done));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) fail(path + "@" + std::to_string(offset + done), std::string("read failed: ") + std::strerror(errno));
    if (got == 0) fail(path + "@" + std::to_string(offset + done), "unexpected end of file");
    done += static_cast<uint64_t>(got);
  }
  return bytes;
}

// Checks a frame and returns its payload span within `framed`.
std::span<const uint8_t> unframe(std::span<const uint8_t> framed, const std::string& path,
                                 uint64_t offset, const char* part) {
  ByteReader r(framed, path, offset);
  uint32_t size = r.get<uint32_t>("frame size");
  r.get<uint32_t>("frame padding");
  uint64_t hash = r.get<uint64_t>("frame checksum");
  if (size != framed.size() - kFrameBytes)
    r.error(std::string(part) + ": size field says " + std::to_string(size) + " bytes, table says " +
            std::to_string(framed.size() - kFrameBytes));
  auto payload = framed.subspan(kFrameBytes);
  if (XXH3_64bits(payload.data(), payload.size()) != hash)
    fail(path + "@" + std::to_string(offset), std::string(part) + ": checksum mismatch (the file is damaged)");
  return payload;
}

// The footer's texture table (version 2), after the object table.
std::vector<std::pair<uint64_t, uint32_t>> read_texture_table(ByteReader& r, uint64_t records_end) {
  std::vector<std::pair<uint64_t, uint32_t>> textures;
  const uint32_t count = r.get<uint32_t>("texture count");
  if (count > r.remaining() / kTextureEntryBytes) r.error("texture table truncated: " + std::to_string(count) + " entries announced");
  textures.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    auto& [offset, size] = textures[i];
    offset = r.get<uint64_t>("texture offset");
    size = r.get<uint32_t>("texture size");
    if (offset < kHeaderBytes || size < kFrameBytes || offset > records_end || size > records_end - offset)
      r.error("texture " + std::to_string(i) + " points outside the file's records");
  }
  if (r.remaining() != 0) r.error("footer has " + std::to_string(r.remaining()) + " trailing bytes");
  return textures;
}

}  // namespace

SceneReader::SceneReader(std::string path) : path_(std::move(path)) {
  if (std::filesystem::is_directory(path_)) fail(path_, "is a directory, expected a scene file");
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) fail(path_, std::string("cannot open: ") + std::strerror(errno));
  try {
    struct stat st;
    if (::fstat(fd_, &st) != 0) fail(path_, std::string("cannot stat: ") + std::strerror(errno));
    const uint64_t file_size = static_cast<uint64_t>(st.st_size);
    if (file_size < kHeaderBytes + kTrailerBytes)
      fail(path_, "too short to be a scene file (" + std::to_string(file_size) + " bytes)");
    auto header = pread_exact(fd_, path_, 0, kHeaderBytes);
    if (std::memcmp(header.data(), "CWWORLD", 7) == 0)
      fail(path_, "is a world file (.cww), not a scene file: give the scene it was built from, or use the world where a command takes one");
    if (std::memcmp(header.data(), kMagic, 8) != 0)
      fail(path_ + "@0", "not a cellwalk scene file (bad magic); give a scene file made by cellwalk generate or import");
    uint32_t version;
    std::memcpy(&version, header.data() + 8, 4);
    if (version != kVersion && version != 1)
      fail(path_ + "@8", "scene format version " + std::to_string(version) + ", this cellwalk reads 1 and " +
                             std::to_string(kVersion) + ": import or generate the scene again with this cellwalk");
    auto trailer_bytes = pread_exact(fd_, path_, file_size - kTrailerBytes, kTrailerBytes);
    ByteReader t(trailer_bytes, path_, file_size - kTrailerBytes);
    const uint64_t footer_offset = t.get<uint64_t>("footer offset");
    const uint64_t footer_bytes = t.get<uint64_t>("footer size");
    if (std::memcmp(trailer_bytes.data() + 16, kEndMagic, 8) != 0)
      t.error("no end marker: the file is truncated or was not finished");
    // Written so no sum can wrap: every field is compared against what the file holds.
    const uint64_t records_end = file_size - kTrailerBytes;
    if (footer_offset < kHeaderBytes || footer_offset > records_end || footer_bytes < kFrameBytes ||
        footer_bytes != records_end - footer_offset)
      t.error("footer position points outside the file");
    auto footer = pread_exact(fd_, path_, footer_offset, footer_bytes);
    auto payload = unframe(footer, path_, footer_offset, "footer");
    ByteReader r(payload, path_, footer_offset + kFrameBytes);
    const uint32_t count = r.get<uint32_t>("object count");
    triangles_ = r.get<uint64_t>("triangle count");
    info_ = decode_scene_info(r);
    if (count > r.remaining() / kEntryBytes) r.error("object table truncated: " + std::to_string(count) + " entries announced");
    entries_.resize(count);
    uint64_t sum = 0;
    for (uint32_t i = 0; i < count; ++i) {
      SceneEntry& e = entries_[i];
      e.offset = r.get<uint64_t>("entry offset");
      e.size = r.get<uint32_t>("entry size");
      e.triangles = r.get<uint32_t>("entry triangles");
      e.color = r.get<uint32_t>("entry colour");
      e.bounds = get_box(r);
      if (e.offset < kHeaderBytes || e.size < kFrameBytes || e.offset > footer_offset ||
          e.size > footer_offset - e.offset)
        r.error("object " + std::to_string(i) + " points outside the file's records");
      sum += e.triangles;
    }
    if (sum != triangles_) r.error("triangle total disagrees with the object table");
    if (version >= 2) textures_ = read_texture_table(r, footer_offset);
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

SceneReader::~SceneReader() {
  if (fd_ >= 0) ::close(fd_);
}

std::vector<uint8_t> SceneReader::read_record(ObjectId id) const {
  if (id >= entries_.size())
    fail(path_, "object " + std::to_string(id) + " does not exist (the scene has " +
                    std::to_string(entries_.size()) + ")");
  const SceneEntry& e = entries_[id];
  auto bytes = pread_exact(fd_, path_, e.offset, e.size);
  bytes_read_ += e.size;
  return bytes;
}

Object SceneReader::decode_record(ObjectId id, std::span<const uint8_t> record) const {
  const SceneEntry& e = entries_.at(id);
  const std::string where = path_ + ": object " + std::to_string(id);
  auto payload = unframe(record, path_, e.offset, ("object " + std::to_string(id)).c_str());
  ByteReader r(payload, path_, e.offset + kFrameBytes);
  Object o;
  o.id = r.get<uint32_t>("object id");
  if (o.id != id) r.error("record holds object " + std::to_string(o.id) + ", expected " + std::to_string(id));
  o.color = r.get<uint32_t>("colour");
  o.bounds = get_box(r);
  o.name = r.get_string("name");
  const uint32_t vertices = r.get<uint32_t>("vertex count");
  const uint32_t indices = r.get<uint32_t>("index count");
  const uint32_t attributes = r.get<uint32_t>("attribute flags");
  if (attributes & ~(kHasNormals | kHasColors | kHasUvs | kHasTexture)) r.error("unknown attribute flags");
  if (attributes & kHasTexture) {
    o.mesh.texture = r.get<uint32_t>("texture");
    if (o.mesh.texture >= textures_.size())
      r.error("samples texture " + std::to_string(o.mesh.texture) + ", but the scene has " +
              std::to_string(textures_.size()));
  }
  o.mesh.positions = r.get_array<Vec3>(vertices, "positions");
  if (attributes & kHasNormals) o.mesh.normals = r.get_array<Vec3>(vertices, "normals");
  if (attributes & kHasColors) o.mesh.colors = r.get_array<Rgba8>(vertices, "colours");
  if (attributes & kHasUvs) o.mesh.uvs = r.get_array<Vec2>(vertices, "texture coordinates");
  o.mesh.indices = r.get_array<uint32_t>(indices, "indices");
  if (r.remaining() != 0) r.error("record has " + std::to_string(r.remaining()) + " trailing bytes");
  validate(o.mesh, where);
  return o;
}

Object SceneReader::read_object(ObjectId id) const { return decode_record(id, read_record(id)); }

TextureImage SceneReader::read_texture(uint32_t index) const {
  if (index >= textures_.size())
    fail(path_, "texture " + std::to_string(index) + " does not exist (the scene has " +
                    std::to_string(textures_.size()) + ")");
  const auto [offset, size] = textures_[index];
  const std::vector<uint8_t> record = pread_exact(fd_, path_, offset, size);
  bytes_read_ += size;
  auto payload = unframe(record, path_, offset, ("texture " + std::to_string(index)).c_str());
  ByteReader r(payload, path_, offset + kFrameBytes);
  TextureImage t;
  t.name = r.get_string("texture name");
  const uint64_t bytes = r.get<uint64_t>("texture byte count");
  if (bytes != r.remaining()) r.error("texture byte count disagrees with its record");
  t.encoded = r.get_array<uint8_t>(bytes, "texture bytes");
  return t;
}

}  // namespace cellwalk
