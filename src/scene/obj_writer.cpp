// ObjWriter: Wavefront OBJ export for inspection in any viewer. One "o" group per object;
// "v x y z [r g b]" (per-vertex colour as floats in [0, 1]), "vn" and "f a//a b//b c//c".
// Coordinates are printed with 9 significant digits, enough to round-trip a float exactly.
#include <cstdarg>
#include <cstdio>
#include <string>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/import.hpp"

namespace cellwalk {

struct ObjWriter::Impl {
  explicit Impl(std::string path) : file(std::move(path)) {}
  AtomicFile file;
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

// printf-style text appended to `out`, for this format's short lines (a name is written as is).
__attribute__((format(printf, 2, 3))) void print(AtomicFile& out, const char* format, ...) {
  char text[128];
  std::va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(text, sizeof text, format, args);
  va_end(args);
  if (n < 0 || static_cast<size_t>(n) >= sizeof text)
    fail(out.path(), "internal: OBJ line too long");
  out.write(std::string_view(text, static_cast<size_t>(n)));
}

}  // namespace

ObjWriter::ObjWriter(std::string path) : impl_(std::make_unique<Impl>(std::move(path))) {
  impl_->file.write("# cellwalk export\n");
}

ObjWriter::~ObjWriter() = default;

void ObjWriter::add(const Object& object) {
  AtomicFile& out = impl_->file;
  const Mesh& m = object.mesh;
  out.write("o " + line_safe(object.name) + "\n");
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Vec3& p = m.positions[i];
    print(out, "v %.9g %.9g %.9g", p.x, p.y, p.z);
    if (!m.colors.empty()) {
      const Rgba8 c = m.colors[i];
      print(out, " %.6g %.6g %.6g", (c & 0xff) / 255.0, (c >> 8 & 0xff) / 255.0,
            (c >> 16 & 0xff) / 255.0);
    }
    out.write("\n");
  }
  for (const Vec3& n : m.normals) print(out, "vn %.6g %.6g %.6g\n", n.x, n.y, n.z);
  const bool normals = !m.normals.empty();
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    out.write("f");
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<unsigned long long>(impl_->vertices + m.indices[t + k] + 1);
      const auto n = static_cast<unsigned long long>(impl_->normals + m.indices[t + k] + 1);
      if (normals) print(out, " %llu//%llu", v, n);
      else print(out, " %llu", v);
    }
    out.write("\n");
  }
  impl_->vertices += m.positions.size();
  impl_->normals += m.normals.size();
}

void ObjWriter::finish() { impl_->file.commit(); }

}  // namespace cellwalk
