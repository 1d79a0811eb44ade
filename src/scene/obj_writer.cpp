// ObjWriter: Wavefront OBJ export for inspection in any viewer. One "o" group per object;
// "v x y z [r g b]" (per-vertex colour as floats in [0, 1]), "vn" and "f a//a b//b c//c".
// Coordinates are printed with 9 significant digits, enough to round-trip a float exactly.
#include <optional>
#include <string>

#include "cellwalk/import.hpp"
#include "scene/output_file.hpp"

namespace cellwalk {

struct ObjWriter::Impl {
  std::optional<detail::OutputFile> file;
  uint64_t vertices = 0;  // written so far: OBJ indices are global and 1-based
  uint64_t normals = 0;
};

namespace {

// A name must stay on its "o" line.
std::string line_safe(const std::string& name) {
  std::string s = name.empty() ? "object" : name;
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32) c = '_';
  return s;
}

}  // namespace

ObjWriter::ObjWriter(std::string path) : impl_(std::make_unique<Impl>()) {
  impl_->file.emplace(std::move(path));
  impl_->file->print("# cellwalk export\n");
}

ObjWriter::~ObjWriter() = default;

void ObjWriter::add(const Object& object) {
  detail::OutputFile& out = *impl_->file;
  const Mesh& m = object.mesh;
  out.print("o %s\n", line_safe(object.name).c_str());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Vec3& p = m.positions[i];
    out.print("v %.9g %.9g %.9g", p.x, p.y, p.z);
    if (!m.colors.empty()) {
      const Rgba8 c = m.colors[i];
      out.print(" %.6g %.6g %.6g", (c & 0xff) / 255.0, (c >> 8 & 0xff) / 255.0,
                (c >> 16 & 0xff) / 255.0);
    }
    out.print("\n");
  }
  for (const Vec3& n : m.normals) out.print("vn %.6g %.6g %.6g\n", n.x, n.y, n.z);
  const bool normals = !m.normals.empty();
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    out.print("f");
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<unsigned long long>(impl_->vertices + m.indices[t + k] + 1);
      const auto n = static_cast<unsigned long long>(impl_->normals + m.indices[t + k] + 1);
      if (normals) out.print(" %llu//%llu", v, n);
      else out.print(" %llu", v);
    }
    out.print("\n");
  }
  impl_->vertices += m.positions.size();
  impl_->normals += m.normals.size();
}

void ObjWriter::finish() { impl_->file->commit(); }

}  // namespace cellwalk
