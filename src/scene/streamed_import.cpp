// Importing a model larger than memory (issue 16, item 1). Three passes over disk, each with
// memory bounded by StreamLimits::memory_bytes whatever the model's size:
//  1. read: the PLY, OFF or OBJ file (OBJ's geometry alone), mapped and released behind the reader, goes into two scratch files,
//     the vertices (position, normal, colour: 28 B) and the triangles (3 × u32);
//  2. normals (when the file has none): each triangle's area-weighted normal added to its
//     corners' through a write-back cache of vertex blocks — the whole mesh's normals, as
//     compute_normals gives them, so patches meet without shading seams;
//  3. partition: triangles by centroid into a 64³ grid counted in one pass, the grid cut by
//     median splits of the counts into boxes of cells that fit the memory, the triangles (with
//     their corners' vertex records) written to each box's range of one scratch file in a second
//     pass; a box still too large (one dense cell) is partitioned again within itself, and each
//     one that fits is read whole, re-indexed and split into patches by split_into_patches
//     (patches.cpp).
// Out-of-core partitioning into spatially coherent chunks is what Nexus and out-of-core
// simplifiers (Lindstrom's OoCS, Cignoni et al.'s OEMM) do before building anything per chunk.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <list>
#include <numeric>
#include <optional>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/process_memory.hpp"
#include "cellwalk/scene/import.hpp"
#include "core/progress.hpp"
#include "scene/readers.hpp"

namespace cellwalk {

namespace {

struct VertexRecord {
  Vec3 position;
  Vec3 normal;
  Rgba8 color;
};
static_assert(sizeof(VertexRecord) == 28);

struct Corner {
  uint32_t vertex;  // in the file, so a bucket can share its corners again
  VertexRecord record;
};
using Triangle = std::array<Corner, 3>;
static_assert(sizeof(Triangle) == 96);

// What holding one triangle of a bucket in memory costs at most: its records (96 B) while the
// mesh is re-indexed, then the mesh and split_into_patches' centroids, order and patch copies.
constexpr uint64_t kLoadBytesPerTriangle = 192;
constexpr int kGridSide = 64;  // the partition's grid: 64³ cells, 2 MiB of counts
constexpr int kMaxDepth = 6;   // below this a bucket too large is cut in file order
constexpr size_t kBucketBufferBytes = 64 << 10;
constexpr size_t kFileBufferBytes = 1 << 20;

// A file with no name: created in `dir` and unlinked at once, so it is gone when closed or
// when the process dies. Writes are buffered; reads see only what was flushed.
class ScratchFile {
 public:
  explicit ScratchFile(const std::string& dir) : dir_(dir) {
    std::string pattern = (std::filesystem::path(dir) / ".cellwalk-import-XXXXXX").string();
    fd_ = ::mkstemp(pattern.data());
    if (fd_ < 0)
      fail(dir, std::string("cannot create a scratch file: ") + std::strerror(errno) +
                    "; pass --temp-dir with a writable folder");
    ::unlink(pattern.c_str());
  }
  ~ScratchFile() { ::close(fd_); }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  void append(const void* data, size_t n) {
    buffer_.append(static_cast<const char*>(data), n);
    if (buffer_.size() >= kFileBufferBytes) write_buffer();
  }
  // After the last append: everything readable, the buffer's memory given back.
  void flush() {
    write_buffer();
    buffer_.shrink_to_fit();
  }
  uint64_t size() const { return flushed_ + buffer_.size(); }

  void write_at(uint64_t offset, const void* data, size_t n) {
    const char* p = static_cast<const char*>(data);
    while (n > 0) {
      const ssize_t w = ::pwrite(fd_, p, n, off_t(offset));
      if (w <= 0) {
        const int e = w < 0 ? errno : ENOSPC;
        fail(dir_, std::string("cannot write scratch data: ") + std::strerror(e) +
                       (e == ENOSPC ? "; free disk space there or pass --temp-dir with a larger disk" : ""));
      }
      p += w;
      n -= size_t(w);
      offset += uint64_t(w);
    }
  }
  void read_at(uint64_t offset, void* data, size_t n) const {
    char* p = static_cast<char*>(data);
    while (n > 0) {
      const ssize_t r = ::pread(fd_, p, n, off_t(offset));
      if (r <= 0) fail(dir_, std::string("cannot read scratch data back: ") + (r < 0 ? std::strerror(errno) : "short file"));
      p += r;
      n -= size_t(r);
      offset += uint64_t(r);
    }
  }

 private:
  void write_buffer() {
    write_at(flushed_, buffer_.data(), buffer_.size());
    flushed_ += buffer_.size();
    buffer_.clear();
  }

  std::string dir_;
  int fd_ = -1;
  uint64_t flushed_ = 0;
  std::string buffer_;
};

// Reads `count` items of T from `file` at `offset` in chunks of about 1 MiB.
template <typename T, typename F>
void for_each_item(const ScratchFile& file, uint64_t offset, uint64_t count, F&& f) {
  std::vector<T> chunk(std::max<size_t>(1, kFileBufferBytes / sizeof(T)));
  for (uint64_t done = 0; done < count;) {
    const size_t n = size_t(std::min<uint64_t>(chunk.size(), count - done));
    file.read_at(offset + done * sizeof(T), chunk.data(), n * sizeof(T));
    for (size_t i = 0; i < n; ++i) f(chunk[i]);
    done += n;
  }
}

// The model file, mapped read-only. Pages behind the reader are given back (MADV_DONTNEED), so
// the mapping's share of the process's resident memory stays within `window` bytes.
// A file cut short by another process while mapped ends the process (SIGBUS), as any mapped
// reader does: import a model that is no longer being written (docs/import.md).
class MappedFile {
 public:
  MappedFile(const std::string& path, uint64_t window) : window_(window) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) fail(path, std::string("cannot open: ") + std::strerror(errno) + "; check the path and its permissions");
    struct stat st {};
    const bool regular = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
    size_ = regular ? uint64_t(st.st_size) : 0;
    void* p = size_ > 0 ? ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0) : MAP_FAILED;
    const int map_error = errno;
    ::close(fd);  // the mapping keeps the file
    if (!regular) fail(path, "is not a regular file");
    if (size_ == 0) fail(path, "is empty");
    if (p == MAP_FAILED) fail(path, std::string("cannot map: ") + std::strerror(map_error));
    data_ = static_cast<uint8_t*>(p);
    ::madvise(data_, size_, MADV_SEQUENTIAL);
  }
  ~MappedFile() { ::munmap(data_, size_); }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  std::span<const uint8_t> bytes() const { return {data_, size_}; }
  // The reader is past `offset`: every whole page before it may go.
  void consumed(uint64_t offset) {
    static const uint64_t page = uint64_t(::sysconf(_SC_PAGESIZE));
    const uint64_t end = offset / page * page;
    if (end < released_ + window_) return;
    ::madvise(data_ + released_, end - released_, MADV_DONTNEED);
    released_ = end;
  }

 private:
  uint64_t window_;
  uint8_t* data_ = nullptr;
  uint64_t size_ = 0;
  uint64_t released_ = 0;
};

// Vertex records in blocks, least recently used evicted, dirty blocks written back.
class VertexCache {
 public:
  static constexpr uint64_t kBlockVertices = 2048;  // 56 KiB

  VertexCache(ScratchFile& file, uint64_t vertices, uint64_t bytes)
      : file_(file), vertices_(vertices),
        capacity_(std::max<uint64_t>(4, bytes / (kBlockVertices * sizeof(VertexRecord)))) {}
  ~VertexCache() = default;  // REQUIRES: flush() after the last write

  // REQUIRES: v < vertices. The reference lives until the next call.
  VertexRecord& at(uint32_t v, bool write) {
    const uint64_t id = v / kBlockVertices;
    auto it = blocks_.find(id);
    if (it == blocks_.end()) it = load(id);
    else lru_.splice(lru_.begin(), lru_, it->second.lru);
    it->second.dirty |= write;
    return it->second.records[v % kBlockVertices];
  }
  void flush() {
    for (auto& [id, block] : blocks_) write_back(id, block);
  }

 private:
  struct Block {
    std::vector<VertexRecord> records;
    bool dirty = false;
    std::list<uint64_t>::iterator lru;
  };

  std::unordered_map<uint64_t, Block>::iterator load(uint64_t id) {
    if (blocks_.size() >= capacity_) {
      const uint64_t victim = lru_.back();
      lru_.pop_back();
      auto v = blocks_.find(victim);
      write_back(victim, v->second);
      blocks_.erase(v);
    }
    Block block;
    const uint64_t first = id * kBlockVertices;
    block.records.resize(size_t(std::min(kBlockVertices, vertices_ - first)));
    file_.read_at(first * sizeof(VertexRecord), block.records.data(), block.records.size() * sizeof(VertexRecord));
    lru_.push_front(id);
    block.lru = lru_.begin();
    return blocks_.emplace(id, std::move(block)).first;
  }
  void write_back(uint64_t id, Block& block) {
    if (!block.dirty) return;
    file_.write_at(id * kBlockVertices * sizeof(VertexRecord), block.records.data(),
                   block.records.size() * sizeof(VertexRecord));
    block.dirty = false;
  }

  ScratchFile& file_;
  uint64_t vertices_;
  uint64_t capacity_;
  std::unordered_map<uint64_t, Block> blocks_;
  std::list<uint64_t> lru_;  // front: most recent
};

// Pass 1: the reader's vertices and triangles into scratch files, placed as they come.
class ScratchBuilder : public detail::MeshBuilder {
 public:
  ScratchBuilder(ScratchFile& vertices, ScratchFile& triangles, const Mat4& m, MappedFile& input,
                 const std::string& name)
      : vertices_(vertices), triangles_(triangles), m_(m),
        normal_matrix_(glm::transpose(glm::inverse(glm::mat3(m)))), input_(input), name_(name),
        progress_("reading " + std::filesystem::path(name).filename().string(), input.bytes().size()) {}

  void begin_vertices(uint64_t, bool normals, bool colors) override {
    normals_ = normals;
    colors_ = colors;
  }
  void vertex(const Vec3& position, const Vec3& normal, Rgba8 color) override {
    VertexRecord r{Vec3(m_ * Vec4(position, 1.0f)), Vec3(0.0f), colors_ ? color : 0};
    const Vec3 a = glm::abs(r.position);
    // All finite and in range (NaN fails the comparisons): only then skip the message's cost.
    if (!(a.x <= kMaxCoordinate && a.y <= kMaxCoordinate && a.z <= kMaxCoordinate)) check_position(r.position, name_, "vertex " + std::to_string(written_));
    if (normals_) {
      if (!std::isfinite(normal.x) || !std::isfinite(normal.y) || !std::isfinite(normal.z))
        fail(name_, "vertex " + std::to_string(written_) +
                        " has a non-finite normal; fix the normals, or remove them all so cellwalk computes them");
      r.normal = normal_matrix_ * normal;
    }
    bounds.extend(r.position);
    vertices_.append(&r, sizeof r);
    ++written_;
  }
  void triangle(uint32_t a, uint32_t b, uint32_t c) override {
    const uint32_t t[3] = {a, b, c};
    triangles_.append(t, sizeof t);
    ++triangle_count;
  }
  void consumed(uint64_t offset) override {
    input_.consumed(offset);
    progress_.update(offset);
  }
  void finish() {
    vertices_.flush();
    triangles_.flush();
    progress_.finish();
  }

  bool normals() const { return normals_; }
  bool colors() const { return colors_; }
  uint64_t vertex_count() const { return written_; }
  Aabb bounds;
  uint64_t triangle_count = 0;

 private:
  ScratchFile& vertices_;
  ScratchFile& triangles_;
  Mat4 m_;
  glm::mat3 normal_matrix_;
  MappedFile& input_;
  const std::string& name_;
  Progress progress_;
  uint64_t written_ = 0;
  bool normals_ = false, colors_ = false;
};

Vec3 centroid(const Triangle& t) {
  return (t[0].record.position + t[1].record.position + t[2].record.position) / 3.0f;
}

// Where the triangles of one partition step come from: the whole mesh (the triangle file and
// the vertex cache) or one bucket's range of a scratch file.
class TriangleSource {
 public:
  virtual ~TriangleSource() = default;
  virtual void for_each(const std::function<void(const Triangle&)>& f) = 0;
  // It will not be read again: what it holds may go.
  virtual void done() {}
};

// The whole mesh, read from the first pass's files through a cache of vertex blocks; done()
// gives back the cache and the files (only buckets are read after it).
class MeshSource : public TriangleSource {
 public:
  MeshSource(std::unique_ptr<ScratchFile> vertices, std::unique_ptr<ScratchFile> triangles, uint64_t vertex_count,
             uint64_t triangle_count, uint64_t cache_bytes)
      : vertices_(std::move(vertices)), triangles_(std::move(triangles)), count_(triangle_count),
        cache_(std::make_unique<VertexCache>(*vertices_, vertex_count, cache_bytes)) {}
  void for_each(const std::function<void(const Triangle&)>& f) override {
    for_each_item<std::array<uint32_t, 3>>(*triangles_, 0, count_, [&](const std::array<uint32_t, 3>& t) {
      Triangle tri;
      for (int k = 0; k < 3; ++k) tri[k] = {t[k], cache_->at(t[k], false)};
      f(tri);
    });
  }
  void done() override {
    cache_.reset();
    triangles_.reset();
    vertices_.reset();
  }

 private:
  std::unique_ptr<ScratchFile> vertices_, triangles_;
  uint64_t count_;
  std::unique_ptr<VertexCache> cache_;
};

class RangeSource : public TriangleSource {
 public:
  RangeSource(const ScratchFile& file, uint64_t first, uint64_t count) : file_(file), first_(first), count_(count) {}
  void for_each(const std::function<void(const Triangle&)>& f) override {
    for_each_item<Triangle>(file_, first_ * sizeof(Triangle), count_, f);
  }

 private:
  const ScratchFile& file_;
  uint64_t first_, count_;
};

// The grid cell of a point of `box` (points on the far faces go in the last cells).
int cell_of(const Vec3& p, const Aabb& box) {
  const Vec3 size = box.size();
  int c[3];
  for (int a = 0; a < 3; ++a) {
    const float f = size[a] > 0.0f ? (p[a] - box.min[a]) / size[a] : 0.0f;
    c[a] = std::clamp(int(f * kGridSide), 0, kGridSide - 1);
  }
  return c[0] + kGridSide * (c[1] + kGridSide * c[2]);
}

// A box of grid cells: [lo, hi) on each axis.
struct CellBox {
  std::array<int, 3> lo{0, 0, 0}, hi{kGridSide, kGridSide, kGridSide};
};

// Triangles per slice of `b` along `axis`.
std::vector<uint64_t> slice_counts(const std::vector<uint64_t>& cells, const CellBox& b, int axis) {
  std::vector<uint64_t> slices(size_t(b.hi[axis] - b.lo[axis]), 0);
  for (int z = b.lo[2]; z < b.hi[2]; ++z)
    for (int y = b.lo[1]; y < b.hi[1]; ++y)
      for (int x = b.lo[0]; x < b.hi[0]; ++x) {
        const int c[3] = {x, y, z};
        slices[size_t(c[axis] - b.lo[axis])] += cells[size_t(x + kGridSide * (y + kGridSide * z))];
      }
  return slices;
}

// The grid cut into boxes of at most `target` triangles (or of one cell) by median splits of
// the counts along the box's longest side: buckets as compact as the grid allows. Empty boxes
// are dropped.
std::vector<CellBox> bucket_boxes(const std::vector<uint64_t>& cells, const Vec3& size, uint64_t target) {
  std::vector<CellBox> out;
  std::vector<CellBox> todo = {CellBox{}};
  while (!todo.empty()) {
    const CellBox b = todo.back();
    todo.pop_back();
    int axis = -1;
    float longest = 0.0f;
    for (int a = 0; a < 3; ++a) {
      const float side = float(b.hi[a] - b.lo[a]) * size[a];
      if (b.hi[a] - b.lo[a] > 1 && (axis < 0 || side > longest)) {
        axis = a;
        longest = side;
      }
    }
    const std::vector<uint64_t> slices = slice_counts(cells, b, axis < 0 ? 0 : axis);
    const uint64_t count = std::accumulate(slices.begin(), slices.end(), uint64_t(0));
    if (count == 0) continue;
    if (count <= target || axis < 0) {
      out.push_back(b);
      continue;
    }
    // The first slice at which half the triangles are behind, kept inside the box.
    uint64_t behind = 0;
    size_t cut = 0;
    while (cut + 1 < slices.size() && behind + slices[cut] <= count / 2) behind += slices[cut++];
    cut = std::max<size_t>(cut, 1);
    CellBox left = b, right = b;
    left.hi[axis] = right.lo[axis] = b.lo[axis] + int(cut);
    todo.push_back(right);
    todo.push_back(left);
  }
  return out;
}

// One partition step's buckets: boxes of cells, which bucket each cell's triangles go to, and
// where each bucket's range starts in the step's scratch file.
struct Buckets {
  std::vector<uint32_t> of_cell;
  std::vector<uint64_t> count, first;
  std::vector<Aabb> box;
};

// The grid's cells cut into at most 2 × max_buckets boxes of about `target` triangles (more
// when that would take more boxes: buffers and bookkeeping stay bounded).
Buckets make_buckets(const std::vector<uint64_t>& cells, const Aabb& box, uint64_t target, size_t max_buckets) {
  std::vector<CellBox> boxes = bucket_boxes(cells, box.size(), target);
  while (boxes.size() > 2 * max_buckets) boxes = bucket_boxes(cells, box.size(), target *= 2);
  Buckets b;
  b.of_cell.assign(cells.size(), 0);
  b.count.assign(boxes.size(), 0);
  b.first.assign(boxes.size(), 0);
  b.box.resize(boxes.size());
  const Vec3 step = box.size() / float(kGridSide);
  for (size_t i = 0; i < boxes.size(); ++i) {
    const CellBox& c = boxes[i];
    b.box[i] = {box.min + Vec3(c.lo[0], c.lo[1], c.lo[2]) * step, box.min + Vec3(c.hi[0], c.hi[1], c.hi[2]) * step};
    for (int z = c.lo[2]; z < c.hi[2]; ++z)
      for (int y = c.lo[1]; y < c.hi[1]; ++y)
        for (int x = c.lo[0]; x < c.hi[0]; ++x) {
          const size_t cell = size_t(x + kGridSide * (y + kGridSide * z));
          b.of_cell[cell] = uint32_t(i);
          b.count[i] += cells[cell];
        }
    if (i > 0) b.first[i] = b.first[i - 1] + b.count[i - 1];
  }
  return b;
}

}  // namespace

struct StreamedModel::Impl {
  std::string file;
  StreamLimits limits;
  uint64_t bucket_triangles = 0;  // a bucket read whole holds at most this many
  size_t max_buckets = 0;         // asked of one partition step (make_buckets allows twice as many)
  std::unique_ptr<ScratchFile> vertices, triangles;
  Aabb bounds;
  uint64_t vertex_count = 0, triangle_count = 0;
  bool colors = false;
  bool done = false;

  // During patches():
  Vec3 move{0.0f};
  const std::function<void(Object&)>* out = nullptr;
  uint64_t patches = 0;
  std::optional<Progress> progress;
  uint64_t emitted = 0;

  Impl(const std::string& f, StreamLimits l)
      : file(f), limits(std::move(l)), vertices(std::make_unique<ScratchFile>(temp_dir())),
        triangles(std::make_unique<ScratchFile>(temp_dir())) {}

  std::string temp_dir() const {
    if (!limits.temp_dir.empty()) return limits.temp_dir;
    const char* t = std::getenv("TMPDIR");
    return t && *t ? t : "/tmp";
  }

  void read(const Mat4& placement) {
    MappedFile input(file, std::max<uint64_t>(limits.memory_bytes / 8, 1 << 20));
    ScratchBuilder builder(*vertices, *triangles, placement, input, file);
    switch (format_of(file)) {
      case ModelFormat::kOff: detail::read_off(input.bytes(), file, builder); break;
      case ModelFormat::kObj: detail::read_obj_geometry(input.bytes(), file, builder); break;
      default: detail::read_ply(input.bytes(), file, builder);
    }
    builder.finish();
    bounds = builder.bounds;
    vertex_count = builder.vertex_count();
    triangle_count = builder.triangle_count;
    colors = builder.colors();
    if (!builder.normals() && triangle_count > 0) accumulate_normals();
  }

  uint64_t cache_bytes() const { return limits.memory_bytes / 4; }

  // Pass 2: compute_normals' sums, out of core (normalised when a bucket is read).
  void accumulate_normals() {
    VertexCache c(*vertices, vertex_count, cache_bytes());
    Progress progress("normals", triangle_count);
    uint64_t done = 0;
    for_each_item<std::array<uint32_t, 3>>(*triangles, 0, triangle_count, [&](const std::array<uint32_t, 3>& t) {
      const Vec3 a = c.at(t[0], false).position, b = c.at(t[1], false).position, d = c.at(t[2], false).position;
      const Vec3 n = glm::cross(b - a, d - a);
      for (uint32_t v : t) c.at(v, true).normal += n;
      if (++done % 65536 == 0) progress.update(done);
    });
    c.flush();
    progress.finish();
  }

  // Splits the triangles `source` gives (`count` of them, centroids within `box`) into buckets
  // that fit, each handed to emit().
  void partition(TriangleSource& source, const Aabb& box, uint64_t count, int depth) {
    if (count <= bucket_triangles) return emit_whole(source, count);
    const Vec3 size = box.size();
    if (depth >= kMaxDepth || std::max({size.x, size.y, size.z}) <= 0.0f) return emit_in_file_order(source);
    const uint64_t target = std::max<uint64_t>(bucket_triangles, (count + max_buckets - 1) / max_buckets);
    Buckets buckets = make_buckets(count_cells(source, box), box, target, max_buckets);
    ScratchFile file(temp_dir());
    distribute(source, box, buckets, file);
    source.done();
    buckets.of_cell = {};
    // A bucket still too large (a dense cell) is partitioned again within its smaller box; one
    // whose centroids all coincide reaches kMaxDepth and is cut in file order.
    for (size_t b = 0; b < buckets.count.size(); ++b) {
      RangeSource range(file, buckets.first[b], buckets.count[b]);
      partition(range, buckets.box[b], buckets.count[b], depth + 1);
    }
  }

  // The triangles of each cell of a 64³ grid over `box`, by centroid.
  static std::vector<uint64_t> count_cells(TriangleSource& source, const Aabb& box) {
    std::vector<uint64_t> cells(size_t(kGridSide) * kGridSide * kGridSide, 0);
    source.for_each([&](const Triangle& t) { ++cells[size_t(cell_of(centroid(t), box))]; });
    return cells;
  }

  // Writes each triangle to its bucket's range of `file`, through a buffer per bucket (all
  // within an eighth of the memory).
  void distribute(TriangleSource& source, const Aabb& box, const Buckets& buckets, ScratchFile& scratch) const {
    const size_t n = buckets.count.size();
    const size_t per_buffer =
        std::clamp<size_t>(size_t(limits.memory_bytes / 8 / sizeof(Triangle) / n), 1, kBucketBufferBytes / sizeof(Triangle));
    std::vector<std::vector<Triangle>> buffers(n);
    std::vector<uint64_t> written(n, 0);
    auto drain = [&](size_t b) {
      // The second pass sees what the first counted (the same records, the same cells): a bucket
      // overflowing its range would overwrite the next one's, so it is checked, not assumed.
      if (written[b] + buffers[b].size() > buckets.count[b]) fail(file, "internal error: a bucket outgrew its count");
      scratch.write_at((buckets.first[b] + written[b]) * sizeof(Triangle), buffers[b].data(),
                    buffers[b].size() * sizeof(Triangle));
      written[b] += buffers[b].size();
      buffers[b].clear();
    };
    source.for_each([&](const Triangle& t) {
      const size_t b = buckets.of_cell[size_t(cell_of(centroid(t), box))];
      if (buffers[b].capacity() == 0) buffers[b].reserve(per_buffer);
      buffers[b].push_back(t);
      if (buffers[b].size() == per_buffer) drain(b);
    });
    for (size_t b = 0; b < n; ++b) drain(b);
  }

  void emit_in_file_order(TriangleSource& source) {
    std::vector<Triangle> chunk;
    chunk.reserve(size_t(bucket_triangles));
    source.for_each([&](const Triangle& t) {
      chunk.push_back(t);
      if (chunk.size() == bucket_triangles) {
        emit(std::move(chunk));
        chunk = {};
        chunk.reserve(size_t(bucket_triangles));
      }
    });
    if (!chunk.empty()) emit(std::move(chunk));
  }

  void emit_whole(TriangleSource& source, uint64_t count) {
    std::vector<Triangle> bucket;
    bucket.reserve(size_t(count));
    source.for_each([&](const Triangle& t) { bucket.push_back(t); });
    source.done();
    emit(std::move(bucket));
  }

  // One bucket as an object (corners shared by file vertex), split into patches.
  void emit(std::vector<Triangle> bucket) {
    Object object;
    object.name = std::filesystem::path(file).stem().string();
    object.mesh = shared_corners(bucket);
    emitted += bucket.size();
    bucket = {};  // before split_into_patches makes its copies
    object.bounds = bounds_of(object.mesh);
    for (Object& patch : split_into_patches(std::move(object), limits.patch_triangles)) {
      patch.name = std::filesystem::path(file).stem().string() + "#" + std::to_string(patches++);
      (*out)(patch);
    }
    progress->update(emitted);
    // The bucket's blocks are free now; the next bucket's may not fit the holes they leave.
    return_freed_heap();
  }

  // The bucket's triangles as a mesh whose corners are shared again by their vertex in the
  // file, moved, with unit normals.
  Mesh shared_corners(const std::vector<Triangle>& bucket) const {
    Mesh mesh;
    std::unordered_map<uint32_t, uint32_t> local;
    local.reserve(bucket.size());
    for (const Triangle& t : bucket)
      for (const Corner& c : t) {
        auto [it, added] = local.emplace(c.vertex, uint32_t(mesh.positions.size()));
        if (added) {
          const float len = glm::length(c.record.normal);
          mesh.positions.push_back(c.record.position + move);
          mesh.normals.push_back(len > 0.0f ? c.record.normal / len : Vec3(0.0f, 1.0f, 0.0f));
          if (colors) mesh.colors.push_back(c.record.color);
        }
        mesh.indices.push_back(it->second);
      }
    return mesh;
  }
};

bool streams_within(const std::string& file, uint64_t memory_bytes, bool split) {
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(file, ec);
  const ModelFormat format = format_of(file);
  if (ec || format == ModelFormat::kGltf) return false;
  // Unsplit, a model is read whole while it can be; an OBJ too, as streamed it loses its groups
  // and materials.
  if (size > detail::kMaxModelBytes) return true;
  return format != ModelFormat::kObj && split && size > memory_bytes / 4;
}

StreamedModel::StreamedModel(const std::string& file, const Mat4& placement, StreamLimits limits) {
  if (format_of(file) == ModelFormat::kGltf)
    fail(file, "glTF is not read streamed (its buffers are read whole, up to 2 GiB); convert it to binary PLY "
               "(e.g. `assimp export " + std::filesystem::path(file).filename().string() + " model.ply`) or import it whole");
  if (limits.patch_triangles == 0) fail(file, "a streamed model is always split: --patch-triangles must be at least 1");
  impl_ = std::make_unique<Impl>(file, std::move(limits));
  Impl& m = *impl_;
  // Patches are cut from buckets: a --patch-triangles above what fits gives smaller patches.
  m.bucket_triangles = std::max<uint64_t>(1, m.limits.memory_bytes / 2 / kLoadBytesPerTriangle);
  // With up to twice as many buckets as asked, their 64 KiB buffers fit M / 8.
  m.max_buckets = std::clamp<size_t>(size_t(m.limits.memory_bytes / 16 / kBucketBufferBytes), 8, 4096);
  m.read(placement);
}

StreamedModel::~StreamedModel() = default;

const Aabb& StreamedModel::bounds() const { return impl_->bounds; }
uint64_t StreamedModel::triangle_count() const { return impl_->triangle_count; }

void StreamedModel::patches(const Vec3& move, const std::function<void(Object&)>& out) {
  Impl& m = *impl_;
  if (m.done) fail(m.file, "its patches were handed on already");
  m.done = true;
  m.move = move;
  m.out = &out;
  if (m.triangle_count == 0) return;  // a point cloud: nothing to draw
  m.progress.emplace("partitioning " + std::filesystem::path(m.file).filename().string(), m.triangle_count);
  MeshSource source(std::move(m.vertices), std::move(m.triangles), m.vertex_count, m.triangle_count, m.cache_bytes());
  m.partition(source, m.bounds, m.triangle_count, 0);
  m.progress->finish();
}

}  // namespace cellwalk
