// The OpenGL 4.5 core renderer: draws a draw list into an offscreen framebuffer (RGBA8 colour,
// R32UI object id + 1, 32-bit float depth) with the GPU mesh cache in front of the provider.
#include "cellwalk/render/renderer.hpp"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <chrono>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "render/far_face_textures.hpp"
#include "render/gpu_mesh_cache.hpp"
#include "render/mesh_textures.hpp"
#include "render/shaders.hpp"
#include "render/text_overlay.hpp"

namespace cellwalk {
namespace {

constexpr std::string_view kWhere = "renderer";

GLuint compile_shader(GLenum stage, const char* source) {
  GLuint shader = glCreateShader(stage);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    std::array<char, 4096> log{};
    glGetShaderInfoLog(shader, GLsizei(log.size()), nullptr, log.data());
    glDeleteShader(shader);
    fail(kWhere, std::string("shader does not compile: ") + log.data());
  }
  return shader;
}

GLuint link_program(const char* vertex_source, const char* fragment_source) {
  GLuint vertex = compile_shader(GL_VERTEX_SHADER, vertex_source);
  GLuint fragment = compile_shader(GL_FRAGMENT_SHADER, fragment_source);
  GLuint program = glCreateProgram();
  glAttachShader(program, vertex);
  glAttachShader(program, fragment);
  glLinkProgram(program);
  glDeleteShader(vertex);  // flagged: freed with the program
  glDeleteShader(fragment);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    std::array<char, 4096> log{};
    glGetProgramInfoLog(program, GLsizei(log.size()), nullptr, log.data());
    glDeleteProgram(program);
    fail(kWhere, std::string("shader program does not link: ") + log.data());
  }
  return program;
}

void require_gl_45() {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major == 0)
    fail(kWhere, "no OpenGL context is current; make one first with GlContext::headless() (no window: EGL "
                 "surfaceless, set EGL_PLATFORM=surfaceless) or a Window, and keep it alive while drawing");
  if (major * 10 + minor < 45) {
    fail(kWhere, "needs OpenGL 4.5, the current context has " + std::to_string(major) + "." +
                     std::to_string(minor));
  }
}

std::array<float, 4> unpack_color(Rgba8 c) {
  return {float(c & 0xFF) / 255.0f, float(c >> 8 & 0xFF) / 255.0f, float(c >> 16 & 0xFF) / 255.0f,
          float(c >> 24) / 255.0f};
}

GLuint make_renderbuffer(GLenum format, int width, int height) {
  GLuint renderbuffer = 0;
  glCreateRenderbuffers(1, &renderbuffer);
  glNamedRenderbufferStorage(renderbuffer, format, width, height);
  return renderbuffer;
}

// Vertex layout of render::GpuMesh; the buffer binding (stride) is set per draw.
GLuint make_mesh_vertex_array() {
  GLuint vao = 0;
  glCreateVertexArrays(1, &vao);
  auto attribute = [vao](GLuint index, GLint size, GLenum type, GLboolean normalized,
                         GLuint offset) {
    glVertexArrayAttribFormat(vao, index, size, type, normalized, offset);
    glVertexArrayAttribBinding(vao, index, 0);
  };
  attribute(render::kPositionAttribute, 3, GL_FLOAT, GL_FALSE, 0);
  attribute(render::kNormalAttribute, 4, GL_INT_2_10_10_10_REV, GL_TRUE, 12);
  attribute(render::kColorAttribute, 4, GL_UNSIGNED_BYTE, GL_TRUE, 16);
  glEnableVertexArrayAttrib(vao, render::kPositionAttribute);
  glEnableVertexArrayAttrib(vao, render::kNormalAttribute);
  return vao;
}

// Vertex layout of render::OverlayVertex, in its own buffer bound at binding 0.
GLuint make_overlay_vertex_array(GLuint buffer) {
  GLuint vao = 0;
  glCreateVertexArrays(1, &vao);
  glVertexArrayAttribFormat(vao, render::kPositionAttribute, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribFormat(vao, render::kColorAttribute, 4, GL_UNSIGNED_BYTE, GL_TRUE, 12);
  for (GLuint attribute : {render::kPositionAttribute, render::kColorAttribute}) {
    glVertexArrayAttribBinding(vao, attribute, 0);
    glEnableVertexArrayAttrib(vao, attribute);
  }
  glVertexArrayVertexBuffer(vao, 0, buffer, 0, sizeof(render::OverlayVertex));
  return vao;
}

}  // namespace

struct Renderer::Impl {
  explicit Impl(const RenderSettings& s)
      : settings(s), cache(s.gpu_budget_bytes), far_textures(s.far_face_budget_bytes) {
    require_gl_45();
    if (s.width <= 0 || s.height <= 0) {
      fail(kWhere, "image size must be positive, got " + std::to_string(s.width) + "x" +
                       std::to_string(s.height));
    }
    create_framebuffer();
    program = link_program(render::kMeshVertexShader, render::kMeshFragmentShader);
    vao = make_mesh_vertex_array();
    overlay_program = link_program(render::kOverlayVertexShader, render::kOverlayFragmentShader);
    backdrop_program = link_program(render::kBackdropVertexShader, render::kBackdropFragmentShader);
    far_program = link_program(render::kFarFaceVertexShader, render::kFarFaceFragmentShader);
    glCreateBuffers(1, &overlay_buffer);
    overlay_vao = make_overlay_vertex_array(overlay_buffer);
  }

  ~Impl() {
    glDeleteVertexArrays(1, &overlay_vao);
    glDeleteBuffers(1, &overlay_buffer);
    glDeleteProgram(overlay_program);
    glDeleteProgram(backdrop_program);
    glDeleteProgram(far_program);
    glDeleteVertexArrays(1, &vao);
    glDeleteProgram(program);
    glDeleteFramebuffers(1, &framebuffer);
    GLuint renderbuffers[] = {color, ids, depth};
    glDeleteRenderbuffers(3, renderbuffers);
  }

  void create_framebuffer() {
    color = make_renderbuffer(GL_RGBA8, settings.width, settings.height);
    ids = make_renderbuffer(GL_R32UI, settings.width, settings.height);
    depth = make_renderbuffer(GL_DEPTH_COMPONENT32F, settings.width, settings.height);
    glCreateFramebuffers(1, &framebuffer);
    glNamedFramebufferRenderbuffer(framebuffer, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
    glNamedFramebufferRenderbuffer(framebuffer, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, ids);
    glNamedFramebufferRenderbuffer(framebuffer, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    GLenum status = glCheckNamedFramebufferStatus(framebuffer, GL_DRAW_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      fail(kWhere, "offscreen framebuffer incomplete (status " + std::to_string(status) + ")");
    }
  }

  // Binds the offscreen targets and the mesh program and clears colour, ids and depth. Sets
  // every piece of GL state it relies on: overlays and the window code change some of it.
  void begin_frame(const Camera& camera) {
    const GLenum color_and_ids[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(framebuffer, 2, color_and_ids);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffer);
    glViewport(0, 0, settings.width, settings.height);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glDisable(GL_SCISSOR_TEST);  // it would clip the clears too
    std::array<float, 4> background = unpack_color(settings.background);
    const GLuint no_object[4] = {kBackgroundId, 0, 0, 0};
    const float far_depth = 1.0f;
    glClearNamedFramebufferfv(framebuffer, GL_COLOR, 0, background.data());
    glClearNamedFramebufferuiv(framebuffer, GL_COLOR, 1, no_object);
    glClearNamedFramebufferfv(framebuffer, GL_DEPTH, 0, &far_depth);
    if (settings.backdrop) draw_backdrop(camera, background);

    glUseProgram(program);
    glBindVertexArray(vao);
    glProgramUniformMatrix4fv(program, render::kViewProjectionUniform, 1, GL_FALSE,
                              glm::value_ptr(camera.view_projection()));
    glProgramUniform3fv(program, render::kEyePositionUniform, 1, glm::value_ptr(camera.position));
  }

  // Colour only, no depth: objects drawn afterwards cover it exactly as they cover a clear.
  void draw_backdrop(const Camera& camera, const std::array<float, 4>& sky) {
    const GLenum color_only[] = {GL_COLOR_ATTACHMENT0, GL_NONE};
    glNamedFramebufferDrawBuffers(framebuffer, 2, color_only);
    glDepthMask(GL_FALSE);
    glDisable(GL_DEPTH_TEST);
    glUseProgram(backdrop_program);
    glBindVertexArray(vao);
    const Mat4 inverse = glm::inverse(camera.view_projection());
    glProgramUniformMatrix4fv(backdrop_program, render::kInverseViewProjectionUniform, 1, GL_FALSE,
                              glm::value_ptr(inverse));
    glProgramUniform3fv(backdrop_program, render::kBackdropEyeUniform, 1, glm::value_ptr(camera.position));
    glProgramUniform3f(backdrop_program, render::kSkyColorUniform, sky[0], sky[1], sky[2]);
    glProgramUniform3f(backdrop_program, render::kGroundUniform, settings.ground_y, settings.ground_grid, settings.ground_haze);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    const GLenum color_and_ids[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(framebuffer, 2, color_and_ids);
    glEnable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
  }

  // The far faces, as background after the clear (and backdrop): no depth test, no depth writes.
  // Leaves the mesh program bound, as begin_frame does.
  void draw_far_faces(const Camera& camera, std::span<const FarFace> faces, RenderStats& stats) {
    if (faces.empty()) return;
    glDepthMask(GL_FALSE);
    glDisable(GL_DEPTH_TEST);
    glUseProgram(far_program);
    glProgramUniformMatrix4fv(far_program, render::kViewProjectionUniform, 1, GL_FALSE,
                              glm::value_ptr(camera.view_projection()));
    for (const FarFace& face : faces) {
      const render::FaceTextures& t = far_textures.get(face, stats.uploaded_bytes);
      glBindTextureUnit(0, t.color);
      glBindTextureUnit(1, t.ids);
      glProgramUniform3fv(far_program, render::kFarOriginUniform, 1, glm::value_ptr(face.origin));
      glProgramUniform3fv(far_program, render::kFarAxisUUniform, 1, glm::value_ptr(face.u));
      glProgramUniform3fv(far_program, render::kFarAxisVUniform, 1, glm::value_ptr(face.v));
      glProgramUniform1ui(far_program, render::kFarFaceIdUniform, pixel_id({face.id, 0, 0, DrawKind::kFarFace}));
      glProgramUniform1i(far_program, render::kFarHasIdsUniform, t.ids != 0);
      const bool fading = face.opacity < 1.0f;
      if (fading) {  // blend the colour attachment only; the ids keep what is underneath
        glEnablei(GL_BLEND, 0);
        glBlendColor(0.0f, 0.0f, 0.0f, std::clamp(face.opacity, 0.0f, 1.0f));
        glBlendFunc(GL_CONSTANT_ALPHA, GL_ONE_MINUS_CONSTANT_ALPHA);
        glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
      }
      glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
      if (fading) {
        glDisablei(GL_BLEND, 0);
        glBlendFunc(GL_ONE, GL_ZERO);
        glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      }
      stats.triangles += 2;
    }
    glEnable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
    glUseProgram(program);
  }

  // Texture unit 0 and the uv attribute for a mesh that samples a texture the source gives;
  // otherwise the mesh is drawn in its colours alone.
  void bind_texture(const render::GpuMesh& mesh, RenderStats& stats) {
    const GLuint texture =
        mesh.texture() != kNoTexture && textures ? textures->get(mesh.texture(), texture_source, stats.uploaded_bytes) : 0;
    glProgramUniform1i(program, render::kTexturedUniform, texture != 0);
    if (texture == 0) {
      glDisableVertexArrayAttrib(vao, render::kUvAttribute);
      return;
    }
    glBindTextureUnit(0, texture);
    glVertexArrayAttribFormat(vao, render::kUvAttribute, 2, GL_FLOAT, GL_FALSE, mesh.uv_offset());
    glVertexArrayAttribBinding(vao, render::kUvAttribute, 0);
    glEnableVertexArrayAttrib(vao, render::kUvAttribute);
  }

  void draw(const render::GpuMesh& mesh, const DrawItem& item, RenderStats& stats) {
    glVertexArrayVertexBuffer(vao, 0, mesh.buffer(), 0, GLsizei(mesh.stride()));
    glVertexArrayElementBuffer(vao, mesh.buffer());
    if (mesh.has_colors()) {
      glEnableVertexArrayAttrib(vao, render::kColorAttribute);
    } else {
      // A disabled attribute reads its current generic value: the item's colour for every vertex.
      glDisableVertexArrayAttrib(vao, render::kColorAttribute);
      glVertexAttrib4Nub(render::kColorAttribute, item.color & 0xFF, item.color >> 8 & 0xFF,
                         item.color >> 16 & 0xFF, item.color >> 24);
    }
    bind_texture(mesh, stats);
    glProgramUniform1ui(program, render::kObjectIdUniform, pixel_id(item));
    for (uint32_t first = 0; first < mesh.index_count();) {
      const uint32_t count = std::min(mesh.index_count() - first, 3 * (kDriverBatchTriangles - queued_triangles));
      glDrawElements(GL_TRIANGLES, GLsizei(count), GL_UNSIGNED_INT,
                     reinterpret_cast<const void*>(uintptr_t(mesh.index_offset() + sizeof(uint32_t) * first)));
      first += count;
      queued_triangles += count / 3;
      if (queued_triangles == kDriverBatchTriangles) finish();
    }
  }

  // Waits for the GPU: the driver's binned triangles and the retired buffers are freed.
  void finish() {
    glFinish();
    cache.gpu_finished();
    queued_triangles = 0;
  }

  // Draws one item from the cache, asking the provider on a miss. Returns false if skipped.
  bool draw_item(const DrawItem& item, const MeshProvider& provider, RenderStats& stats) {
    if (item.id >= kMaxPixelId) fail("render", "draw item id " + std::to_string(item.id) + " is past the id buffer's range");
    const render::MeshKey key{item.id, item.lod, uint8_t(item.kind)};
    const render::GpuMesh* resident = item.transient ? nullptr : cache.find(key);
    if (resident != nullptr) {
      ++stats.gpu_hits;
      draw(*resident, item, stats);
      stats.triangles += resident->index_count() / 3;
      return true;
    }
    ++stats.gpu_misses;
    const Mesh* mesh = provider(item);
    if (mesh == nullptr) return false;
    uint64_t bytes = render::GpuMesh::bytes_for(*mesh);
    stats.uploaded_bytes += bytes;
    stats.triangles += mesh->triangle_count();
    if (!item.transient && bytes <= cache.budget()) {
      draw(*cache.insert(key, *mesh), item, stats);
    } else {
      cache.make_room(bytes);
      draw(render::GpuMesh(*mesh), item, stats);  // transient: deleted after the draw is queued
      cache.retire(bytes);
    }
    return true;
  }

  // Ascending (kind, id, lod); stable so equal keys keep the caller's order.
  const std::vector<const DrawItem*>& sorted(std::span<const DrawItem> items) {
    order.clear();
    for (const DrawItem& item : items) order.push_back(&item);
    std::stable_sort(order.begin(), order.end(), [](const DrawItem* a, const DrawItem* b) {
      return std::tie(a->kind, a->id, a->lod) < std::tie(b->kind, b->id, b->lod);
    });
    return order;
  }

  // Draws overlay vertices over the colour target only, on top of everything. The buffer is
  // respecified per call (orphaned), so a draw still in flight keeps its old storage.
  void draw_overlay(const std::vector<render::OverlayVertex>& vertices, GLenum mode,
                    const Mat4& matrix) {
    if (vertices.empty()) return;
    glNamedBufferData(overlay_buffer, GLsizeiptr(vertices.size() * sizeof(render::OverlayVertex)),
                      vertices.data(), GL_STREAM_DRAW);
    const GLenum color_only[] = {GL_COLOR_ATTACHMENT0, GL_NONE};
    glNamedFramebufferDrawBuffers(framebuffer, 2, color_only);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffer);
    glViewport(0, 0, settings.width, settings.height);
    glDisable(GL_DEPTH_TEST);
    glUseProgram(overlay_program);
    glBindVertexArray(overlay_vao);
    glProgramUniformMatrix4fv(overlay_program, render::kOverlayMatrixUniform, 1, GL_FALSE,
                              glm::value_ptr(matrix));
    glDrawArrays(mode, 0, GLsizei(vertices.size()));
  }

  void read_attachment(GLenum attachment, GLenum format, GLenum type, void* out) const {
    glNamedFramebufferReadBuffer(framebuffer, attachment);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, settings.width, settings.height, format, type, out);
  }

  RenderSettings settings;
  render::GpuMeshCache cache;
  render::FarFaceTextures far_textures;
  std::unique_ptr<render::MeshTextures> textures;  // once a texture source is set
  TextureSource texture_source;
  GLuint color = 0, ids = 0, depth = 0, framebuffer = 0;
  GLuint program = 0, vao = 0;
  GLuint overlay_program = 0, overlay_vao = 0, overlay_buffer = 0;
  GLuint backdrop_program = 0;
  GLuint far_program = 0;
  std::vector<const DrawItem*> order;
  std::vector<render::OverlayVertex> overlay_vertices;
  uint32_t queued_triangles = 0;  // since the last finish(); at most kDriverBatchTriangles
};

void append_box_lines(const Aabb& b, Rgba8 color, std::vector<LineSegment>& out) {
  auto corner = [&](int i) {
    return Vec3((i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y, (i & 4) ? b.max.z : b.min.z);
  };
  for (int i = 0; i < 8; ++i)
    for (int bit : {1, 2, 4})
      if (!(i & bit)) out.push_back({corner(i), corner(i | bit), color});
}

Renderer::Renderer(const RenderSettings& settings) : impl_(std::make_unique<Impl>(settings)) {}

Renderer::~Renderer() = default;

RenderStats Renderer::render(const Camera& camera, std::span<const DrawItem> items,
                             const MeshProvider& provider, std::span<const FarFace> far_faces) {
  auto start = std::chrono::steady_clock::now();
  RenderStats stats;
  impl_->begin_frame(camera);
  impl_->draw_far_faces(camera, far_faces, stats);
  const DrawItem* previous = nullptr;
  for (const DrawItem* item : impl_->sorted(items)) {
    if (!impl_->draw_item(*item, provider, stats)) continue;
    if (previous == nullptr || previous->kind != item->kind || previous->id != item->id) ++stats.objects;
    previous = item;
  }
  impl_->finish();
  stats.gpu_resident_bytes = impl_->cache.resident_bytes() + impl_->far_textures.resident_bytes() +
                             (impl_->textures ? impl_->textures->resident_bytes() : 0);
  stats.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

void Renderer::set_texture_source(TextureSource source) {
  Impl& impl = *impl_;
  const RenderSettings& s = impl.settings;
  const uint64_t share = std::min(s.max_texture_budget_bytes,
                                  uint64_t(double(s.gpu_budget_bytes) * std::clamp(s.texture_share, 0.0, 1.0)));
  impl.textures = std::make_unique<render::MeshTextures>(share);
  impl.cache.set_budget(s.gpu_budget_bytes - share);
  impl.finish();  // the evicted meshes' storage is freed before the next frame
  impl.texture_source = std::move(source);
}

void Renderer::draw_lines(const Camera& camera, std::span<const LineSegment> segments) {
  std::vector<render::OverlayVertex>& vertices = impl_->overlay_vertices;
  vertices.clear();
  for (const LineSegment& segment : segments) {
    vertices.push_back({segment.a, segment.color});
    vertices.push_back({segment.b, segment.color});
  }
  impl_->draw_overlay(vertices, GL_LINES, camera.view_projection());
}

void Renderer::draw_text(float x, float y, std::string_view text, Rgba8 color, float scale, std::optional<Rgba8> panel) {
  constexpr float kMargin = 4.0f;
  const RenderSettings& s = impl_->settings;
  const std::string wrapped = render::wrap_text(text, std::max(float(s.width) - x - kMargin, 1.0f), scale);
  std::vector<render::OverlayVertex>& vertices = impl_->overlay_vertices;
  vertices.clear();
  if (panel) {
    const Vec2 size = render::text_size(wrapped, scale);
    render::append_rectangle(x - kMargin, y - kMargin, size.x + 2 * kMargin, size.y + 2 * kMargin, *panel, vertices);
  }
  render::append_text(x, y, wrapped, color, scale, vertices);
  // Pixels, y down from the top-left corner, as stb_easy_font lays text out.
  Mat4 pixels = glm::ortho(0.0f, float(s.width), float(s.height), 0.0f, -1.0f, 1.0f);
  impl_->draw_overlay(vertices, GL_TRIANGLES, pixels);
}

Image Renderer::read_color() const {
  Image image{impl_->settings.width, impl_->settings.height, {}};
  image.rgba.resize(size_t(image.width) * image.height * 4);
  impl_->read_attachment(GL_COLOR_ATTACHMENT0, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
  return image;
}

IdImage Renderer::read_ids() const {
  IdImage image{impl_->settings.width, impl_->settings.height, {}};
  image.ids.resize(size_t(image.width) * image.height);
  impl_->read_attachment(GL_COLOR_ATTACHMENT1, GL_RED_INTEGER, GL_UNSIGNED_INT, image.ids.data());
  return image;
}

std::vector<float> Renderer::read_depth() const {
  std::vector<float> depth(size_t(impl_->settings.width) * impl_->settings.height);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, impl_->framebuffer);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, impl_->settings.width, impl_->settings.height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  return depth;
}

void Renderer::present(int window_width, int window_height) const {
  const RenderSettings& s = impl_->settings;
  glNamedFramebufferReadBuffer(impl_->framebuffer, GL_COLOR_ATTACHMENT0);
  bool same_size = window_width == s.width && window_height == s.height;
  glBlitNamedFramebuffer(impl_->framebuffer, 0, 0, 0, s.width, s.height, 0, 0, window_width,
                         window_height, GL_COLOR_BUFFER_BIT, same_size ? GL_NEAREST : GL_LINEAR);
}

const RenderSettings& Renderer::settings() const {
  return impl_->settings;
}

void fit_backdrop(RenderSettings& settings, const Aabb& world_bounds) {
  if (world_bounds.empty()) return;
  settings.ground_y = world_bounds.min.y;
  const float extent = std::max({world_bounds.size().x, world_bounds.size().z, 1e-3f});
  settings.ground_grid = std::min(10.0f, std::pow(10.0f, std::round(std::log10(extent / 10.0f))));
  settings.ground_haze = 30.0f * extent;
}

}  // namespace cellwalk
