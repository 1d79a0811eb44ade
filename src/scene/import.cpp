// Model import: format detection, reading files with clear errors, and the dispatch from
// parse_model to the per-format readers (off_reader.cpp, ply_reader.cpp, obj_reader.cpp,
// gltf_reader.cpp), plus the steps every reader shares.
#include "cellwalk/scene/import.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "cellwalk/core/error.hpp"
#include "scene/readers.hpp"

namespace cellwalk {

namespace detail {

std::vector<uint8_t> read_whole_file(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) fail(path, "no such file");
  if (std::filesystem::is_directory(status)) fail(path, "is a directory, not a model file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) fail(path, "cannot get the size: " + ec.message());
  if (size == 0) fail(path, "is empty");
  if (size > kMaxModelBytes)
    fail(path, "is " + std::to_string(size) + " bytes; models over " +
                   std::to_string(kMaxModelBytes) + " bytes are not read whole: convert it to PLY, which import reads streamed");
  std::vector<uint8_t> bytes(size);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size)))
    fail(path, "read failed after " + std::to_string(in.gcount()) + " bytes");
  return bytes;
}

uint8_t color_channel(double v, double scale) {
  const double x = v / scale * 255.0;
  return x > 0.0 ? static_cast<uint8_t>(std::min(x, 255.0) + 0.5) : 0;
}

std::string format_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

void finish_object(Object& object, const std::string& name) {
  validate(object.mesh, name);
  if (object.mesh.normals.empty()) compute_normals(object.mesh);
  object.bounds = bounds_of(object.mesh);
}

std::optional<TextureImage> checked_texture(TextureImage texture, const std::string& where) {
  try {
    verify_texture(texture.encoded, where);
    return texture;
  } catch (const Error& e) {
    std::fprintf(stderr, "note: %s; its meshes are drawn untextured\n", e.what());
    return std::nullopt;
  }
}

std::optional<TextureImage> read_texture_file(const std::string& uri, const std::string& base_dir,
                                              const std::string& model) {
  if (base_dir.empty()) return std::nullopt;
  const std::filesystem::path file = (std::filesystem::path(base_dir) / uri).lexically_normal();
  const auto rel = file.lexically_relative(base_dir);
  if (rel.empty() || *rel.begin() == "..") {
    std::fprintf(stderr, "note: %s: texture '%s' lies outside the model's folder; its meshes are drawn untextured\n",
                 model.c_str(), uri.c_str());
    return std::nullopt;
  }
  std::vector<uint8_t> bytes;
  try {
    bytes = read_whole_file(file.string());
  } catch (const Error& e) {
    std::fprintf(stderr, "note: %s: texture '%s' not read (%s); its meshes are drawn untextured\n", model.c_str(),
                 uri.c_str(), e.what());
    return std::nullopt;
  }
  return checked_texture({file.filename().string(), std::move(bytes)}, file.string());
}

void MeshCollector::begin_vertices(uint64_t count, bool normals, bool colors) {
  // Readers check the count against the bytes left before they call this.
  object.mesh.positions.reserve(count);
  normals_ = normals;
  colors_ = colors;
}

void MeshCollector::vertex(const Vec3& position, const Vec3& normal, Rgba8 color) {
  object.mesh.positions.push_back(position);
  if (normals_) object.mesh.normals.push_back(normal);
  if (colors_) object.mesh.colors.push_back(color);
}

void MeshCollector::triangle(uint32_t a, uint32_t b, uint32_t c) {
  object.mesh.indices.insert(object.mesh.indices.end(), {a, b, c});
}

Object read_ply(Bytes bytes, const std::string& name) {
  MeshCollector collector;
  read_ply(bytes, name, collector);
  return std::move(collector.object);
}

Object read_off(Bytes bytes, const std::string& name) {
  MeshCollector collector;
  read_off(bytes, name, collector);
  return std::move(collector.object);
}

void append_fan(std::vector<uint32_t>& indices, std::span<const uint32_t> polygon) {
  for_each_fan_triangle(polygon, [&](uint32_t a, uint32_t b, uint32_t c) { indices.insert(indices.end(), {a, b, c}); });
}

}  // namespace detail

namespace {

ImportedModel parse(ModelFormat format, std::span<const uint8_t> bytes, const std::string& name,
                    ObjectId first_id, const std::string& base_dir) {
  if (bytes.empty()) fail(name, "is empty");
  if (format == ModelFormat::kGltf) {
    ImportedModel model = detail::read_gltf(bytes, name, first_id, base_dir);
    if (model.objects.empty()) fail(name, "the scene has no mesh node with triangles");
    return model;
  }
  ImportedModel model;
  std::vector<Object>& objects = model.objects;
  if (format == ModelFormat::kObj) {
    model = detail::read_obj(bytes, name, base_dir);
  } else {
    objects.push_back(format == ModelFormat::kOff ? detail::read_off(bytes, name) : detail::read_ply(bytes, name));
    objects.back().name = std::filesystem::path(name).stem().string();
  }
  // A point cloud is accepted (it has vertices); a file with none is not a model at all.
  if (objects.empty() || objects.front().mesh.positions.empty()) fail(name, "holds no vertices");
  for (size_t i = 0; i < objects.size(); ++i) {
    objects[i].id = first_id + static_cast<ObjectId>(i);
    detail::finish_object(objects[i], objects.size() > 1 ? name + ": " + objects[i].name : name);
  }
  return model;
}

}  // namespace

ModelFormat format_of(const std::string& file) {
  std::string ext = std::filesystem::path(file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".obj") return ModelFormat::kObj;
  if (ext == ".ply") return ModelFormat::kPly;
  if (ext == ".off") return ModelFormat::kOff;
  if (ext == ".gltf" || ext == ".glb") return ModelFormat::kGltf;
  fail(file, "unknown model format '" + ext + "'; expected .obj, .ply, .off, .gltf or .glb");
}

ImportedModel parse_model(ModelFormat format, std::span<const uint8_t> bytes,
                          const std::string& name, ObjectId first_id) {
  return parse(format, bytes, name, first_id, "");
}

ImportedModel import_model(const std::string& file, ObjectId first_id) {
  const ModelFormat format = format_of(file);
  const std::vector<uint8_t> bytes = detail::read_whole_file(file);
  // Only a .gltf beside its .bin buffers and images and an .obj beside its .mtl files and
  // images read other files.
  const std::string base_dir =
      format == ModelFormat::kGltf || format == ModelFormat::kObj
          ? std::filesystem::absolute(file).parent_path().lexically_normal().string()
          : "";
  return parse(format, bytes, file, first_id, base_dir);
}

}  // namespace cellwalk
