// Importers for OBJ, PLY, OFF and glTF 2.0 / GLB, and exporters for inspection.
// Every parser checks what it reads (counts, index ranges, finite coordinates, sizes against
// the file's length) and throws Error "<file>[:line|@offset]: <problem>"; none crashes on any
// input (each has a libFuzzer target in fuzz/).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/scene/scene.hpp"

namespace cellwalk {

enum class ModelFormat { kObj, kPly, kOff, kGltf };

// By extension (.obj .ply .off .gltf .glb, case-insensitive); throws Error otherwise.
ModelFormat format_of(const std::string& file);

// What a model file holds: its objects, and the base-colour textures they sample (a mesh's
// `texture` indexes `textures`, from 0 for each model: the images its materials show).
struct ImportedModel {
  std::vector<Object> objects;
  std::vector<TextureImage> textures;
};

// Parses a model held in memory. `name` is used in error messages and object names.
// glTF files give one object per triangle primitive (node transforms applied), OBJ files one
// per o/g group and texture its materials show; the others give one object. Objects get ids first_id,
// first_id + 1, ...; normals are computed when absent. Textures: glTF's baseColorTexture (with
// its TEXCOORD_n) and OBJ's map_Kd (with vt), from the file itself or, when read from a file,
// image files beside it; parsing from memory reads no other file, and a texture it cannot
// read leaves its meshes untextured.
ImportedModel parse_model(ModelFormat format, std::span<const uint8_t> bytes,
                          const std::string& name, ObjectId first_id = 0);

// Reads and parses a file (a directory, an empty or unreadable file is an Error).
ImportedModel import_model(const std::string& file, ObjectId first_id = 0);

// Splits an object of more than `max_triangles` triangles into spatial patches of at most that
// many (recursive median splits of triangle centroids along the longest axis), each with its
// own vertices (normals and colours carried, so seams shade alike), named NAME#k, with the
// object's id and colour. The patches partition the triangles. REQUIRES: max_triangles > 0.
std::vector<Object> split_into_patches(Object object, size_t max_triangles);

// Importing a model larger than memory (streamed_import.cpp): a PLY, OFF or OBJ file (OBJ's
// geometry alone: one mesh, no groups or materials) is read once into
// scratch files, its triangles partitioned out of core into spatial buckets that fit
// `memory_bytes`, and each bucket split into patches as split_into_patches does. Whatever the
// model's size, the import holds about memory_bytes (the cache of vertices, the bucket in hand,
// the buckets' write buffers); the scratch files take about 28 B per vertex plus 108 B per
// triangle of disk in `temp_dir`, and are unlinked at once (nothing is left if the process dies).
struct StreamLimits {
  uint64_t memory_bytes = uint64_t(1) << 30;
  size_t patch_triangles = 16384;  // REQUIRES: > 0 (a streamed model is always split)
  std::string temp_dir;            // empty: the system's (TMPDIR or /tmp)
};

// Whether import reads `file` streamed: a PLY, OFF or OBJ over the 2 GiB read whole, or, when it
// is to be `split` into patches, a PLY or OFF whose import in memory could take more than
// `memory_bytes` (about four times its size).
bool streams_within(const std::string& file, uint64_t memory_bytes, bool split);

class StreamedModel {
 public:
  // Reads `file` (PLY, ascii or binary, OFF, or OBJ's geometry), its positions and normals transformed by `placement`.
  // Errors name the file and byte or line, as import_model's do.
  StreamedModel(const std::string& file, const Mat4& placement, StreamLimits limits);
  ~StreamedModel();
  StreamedModel(const StreamedModel&) = delete;
  StreamedModel& operator=(const StreamedModel&) = delete;

  const Aabb& bounds() const;
  uint64_t triangle_count() const;

  // Hands `out` each patch in spatial order (at most limits.patch_triangles triangles, fewer
  // when a bucket that fits memory_bytes holds fewer; none for a point cloud; moved by
  // `move`, named STEM#k, id 0: the caller numbers them); together they hold every triangle of
  // the file once, with the normals of the whole mesh (area-weighted when the file has none).
  // Call once.
  void patches(const Vec3& move, const std::function<void(Object&)>& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Where an imported model goes: first its up axis is turned to +y, then it is scaled, then
// moved by `offset`.
struct Placement {
  bool z_up = false;  // the model's up is +z (CAD, many scans)
  float scale = 1.0f;
  Vec3 offset{0.0f};
};
Mat4 placement_matrix(const Placement& placement);
// Transforms the object's mesh (normals too) and recomputes its bounds.
void place(Object& object, const Mat4& m);

// Exporters: write the objects they receive; finish() completes the file (written to a
// temporary name, renamed on finish).
class ObjWriter : public ObjectSink {
 public:
  explicit ObjWriter(std::string path);
  ~ObjWriter() override;
  void add(const Object& object) override;
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// glTF 2.0 with the binary buffer in a ".bin" beside it (or one .glb when path ends in .glb);
// one mesh and node per object, vertex colours as COLOR_0.
class GltfWriter : public ObjectSink {
 public:
  explicit GltfWriter(std::string path);
  ~GltfWriter() override;
  void add(const Object& object) override;
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
