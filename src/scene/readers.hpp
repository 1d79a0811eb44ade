// The per-format model readers behind parse_model (import.cpp), and the cursors they share.
// Each reader checks every count against the bytes left before allocating, every index
// against the vertices read, and ends with validate(); errors are one line:
// "<name>:<line>: <problem>" for text and "<name>@<byte offset>: <problem>" for binary.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cellwalk/scene/import.hpp"
#include "cellwalk/scene/mesh.hpp"

namespace cellwalk::detail {

using Bytes = std::span<const uint8_t>;

// Calls f(a, b, c) for each triangle of the fan (v0, v[i], v[i+1]) of a convex polygon, the
// triangulation every polygon format here uses.
template <typename F>
void for_each_fan_triangle(std::span<const uint32_t> v, F&& f) {
  for (size_t i = 2; i < v.size(); ++i) f(v[0], v[i - 1], v[i]);
}

// Receives a single-mesh model as a reader parses it, so that the model need not be held
// whole: the in-memory import collects it, the streamed one (streamed_import.cpp) writes it to
// scratch files. Calls come in the file's order; indices were checked against the vertex count.
class MeshBuilder {
 public:
  virtual ~MeshBuilder() = default;
  // Once, before the vertices: how many there are (0 when the file does not say) and whether they
  // carry normals and colours.
  virtual void begin_vertices(uint64_t count, bool normals, bool colors) = 0;
  // `normal` and `color` are meaningful only when begin_vertices said so.
  virtual void vertex(const Vec3& position, const Vec3& normal, Rgba8 color) = 0;
  // One triangle of a polygon's fan.
  virtual void triangle(uint32_t a, uint32_t b, uint32_t c) = 0;
  // The reader has read the input up to byte `offset` (now and then, and once at the end).
  virtual void consumed(uint64_t /*offset*/) {}

  // A convex polygon, as its fan.
  void polygon(std::span<const uint32_t> v) {
    for_each_fan_triangle(v, [this](uint32_t a, uint32_t b, uint32_t c) { triangle(a, b, c); });
  }
};

// Keeps what it is given: the import in memory.
class MeshCollector : public MeshBuilder {
 public:
  void begin_vertices(uint64_t count, bool normals, bool colors) override;
  void vertex(const Vec3& position, const Vec3& normal, Rgba8 color) override;
  void triangle(uint32_t a, uint32_t b, uint32_t c) override;
  Object object;

 private:
  bool normals_ = false, colors_ = false;
};

// How often readers tell their builder how far they are (MeshBuilder::consumed), in items: often
// enough that the bytes between two reports stay small next to any memory bound.
constexpr uint64_t kItemsBetweenReports = 1 << 10;

// The single-mesh readers into a builder. REQUIRES of each: `bytes` outlives the call.
void read_ply(Bytes bytes, const std::string& name, MeshBuilder& out);
void read_off(Bytes bytes, const std::string& name, MeshBuilder& out);
// An OBJ's geometry alone, for the streamed import: "v" positions (colours dropped) and "f"
// polygons, checked as read_obj checks them; groups, materials, vt and vn are not kept.
void read_obj_geometry(Bytes bytes, const std::string& name, MeshBuilder& out);

// Single-object formats return the object unfinished: positions, indices and whatever
// normals/colours the file had; finish_object() (import.cpp) does the rest.
Object read_off(Bytes bytes, const std::string& name);
Object read_ply(Bytes bytes, const std::string& name);

// One unfinished object per o/g group and textured material (obj_reader.cpp); .mtl files
// and the images they name are read from `base_dir` only when it is not empty.
ImportedModel read_obj(Bytes bytes, const std::string& name, const std::string& base_dir);

// One finished object per triangle primitive, ids from first_id. External buffers ("x.bin")
// and images are read from `base_dir` only when it is not empty; parsing from memory never
// touches the disk.
ImportedModel read_gltf(Bytes bytes, const std::string& name, ObjectId first_id,
                        const std::string& base_dir);

// The bytes of the image file `uri` names below `base_dir` (empty: none), or nullopt with
// a note on stderr when it cannot be read or is not a PNG/JPEG: a model whose texture is
// missing still imports, untextured (many exported models name files they were not shipped with).
std::optional<TextureImage> read_texture_file(const std::string& uri, const std::string& base_dir,
                                              const std::string& model);

// `texture` when it decodes whole (verify_texture), else nullopt with a note naming `where`.
std::optional<TextureImage> checked_texture(TextureImage texture, const std::string& where);

// A glTF (JSON, or GLB when `glb`) whose buffer views use EXT_meshopt_compression (or
// KHR_meshopt_compression) as an equivalent GLB with those views decoded into one binary
// chunk and the extension removed; empty when no view is compressed (gltf_meshopt.cpp).
// REQUIRES: a GLB's framing was checked.
std::vector<uint8_t> decode_meshopt_compression(Bytes file, bool glb, const std::string& name, const std::string& base_dir);

// The same for primitives compressed with KHR_draco_mesh_compression: each decoded with
// libdraco into float attributes and 32-bit indices (gltf_draco.cpp).
std::vector<uint8_t> decode_draco_compression(Bytes file, bool glb, const std::string& name, const std::string& base_dir);

// The bytes of a file; an Error names it when it is a directory, empty, unreadable or larger
// than kMaxModelBytes.
constexpr uint64_t kMaxModelBytes = uint64_t(2) << 30;
std::vector<uint8_t> read_whole_file(const std::string& path);

// A colour channel in 0..255 from a value on `scale` (1 for [0, 1] floats, 255 for bytes);
// out-of-range values clamp and NaN gives 0 (a float-to-int cast of NaN is undefined).
uint8_t color_channel(double v, double scale);

// A value read as a double (an index, a count) for a message: "12", "1.5", "nan".
std::string format_number(double v);

// Validates the mesh, computes normals when absent and sets the bounds.
void finish_object(Object& object, const std::string& name);

// Appends the fan of a convex polygon (for_each_fan_triangle). REQUIRES: polygon.size() >= 3.
void append_fan(std::vector<uint32_t>& indices, std::span<const uint32_t> polygon);

// Walks a text model by tokens, counting lines for error messages. `comment` starts a comment
// that runs to the end of the line ('\0': the format has none).
class TextCursor {
 public:
  TextCursor(Bytes bytes, std::string name, char comment);

  // The next token, across line ends and comments; empty at the end of the input.
  std::string_view token();
  // The next token on the current line; empty at the line's end (the newline is not consumed).
  std::string_view token_in_line();
  // Skips the rest of the current line, including its newline.
  void next_line();
  // The rest of the current line without its newline (for header lines such as PLY's).
  std::string_view rest_of_line();

  bool at_end() const { return pos_ >= text_.size(); }
  size_t offset() const { return pos_; }
  size_t remaining() const { return text_.size() - pos_; }
  size_t line() const { return line_; }

  // Converters that fail with this cursor's position when the token is not what is asked.
  double to_double(std::string_view token, std::string_view what) const;
  int64_t to_int(std::string_view token, std::string_view what) const;
  // A count the rest of the input must be able to hold: count * min_bytes_each <= remaining().
  uint64_t to_count(std::string_view token, std::string_view what, size_t min_bytes_each) const;

  // "<name>:<line>"
  std::string where() const;
  [[noreturn]] void fail(std::string_view what) const;

 private:
  void check_not_utf16(Bytes bytes) const;
  void skip_blanks_in_line();

  std::string_view text_;
  std::string name_;
  char comment_;
  size_t pos_ = 0;
  size_t line_ = 1;
};

}  // namespace cellwalk::detail
