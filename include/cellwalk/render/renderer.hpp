// The OpenGL 4.5 core renderer: one code path, two ways to get a context (headless EGL on the
// surfaceless platform, or a GLFW window). Renders a draw list into colour, depth and a
// per-object id buffer with fixed, deterministic lighting.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cellwalk/core/camera.hpp"
#include "cellwalk/render/image.hpp"
#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/scene/texture.hpp"

namespace cellwalk {

// Where llvmpipe rasterises. Its worker threads bin every frame's triangles in heap blocks
// whose resident size under CPU load varies by up to ~18 MiB between runs (docs/design.md,
// Memory), so a run held to a memory budget rasterises on the calling thread instead
// (LP_NUM_THREADS=0, unless the user set it). Measured no slower at a walk's sizes.
enum class Rasteriser { kWorkerThreads, kCallingThread };

// A current OpenGL 4.5 core context. Creating one makes it current on the calling thread;
// destroying it makes current again the headless context that was current before (contexts
// nest: destroy them in reverse order of making).
class GlContext {
 public:
  virtual ~GlContext() = default;
  // Headless: EGL with the surfaceless platform (Mesa llvmpipe without a GPU or X server).
  // Throws Error saying what is missing (e.g. Mesa's EGL) when no context can be made.
  // `rasteriser` takes effect for the process's first headless context (Mesa reads it when
  // the display opens).
  static std::unique_ptr<GlContext> headless(Rasteriser rasteriser = Rasteriser::kWorkerThreads);
  virtual std::string renderer_name() const = 0;  // GL_RENDERER
};

// What a draw item is. Its id means a different thing for each kind; the renderer keys its GPU
// cache and its draw order on (kind, id, lod), so ids of different kinds never meet.
enum class DrawKind : uint8_t {
  kObject = 0,     // an object of the world: id is its ObjectId, lod its level
  kAggregate = 1,  // an internal LOD of a hierarchy node (HDoV-tree, scene tree): id is the node
  kFarFace = 2,    // a far-field image on a view cell's face (stratified rendering): id is the face
  kPatch = 3,      // a view-dependent patch (vsplit DAG): id is the patch
};

// What to draw: an object at one of its levels of detail, or one of the other kinds above.
struct DrawItem {
  uint32_t id = 0;
  uint32_t lod = 0;
  Rgba8 color = rgba8(200, 200, 200);  // used when the mesh has no per-vertex colours
  DrawKind kind = DrawKind::kObject;
  // Its mesh changes from frame to frame (a view-dependent client's): drawn from a transient
  // buffer and never cached, so no stale copies fill the cache.
  bool transient = false;
};

// The value an item writes into the id buffer: object id + 1 for objects (0 is the
// background), and for other kinds a value with the kind in the top 4 bits, which no object's
// pixel has. REQUIRES: id < kMaxPixelId (objects past it are refused when drawn).
inline constexpr uint32_t kMaxPixelId = (1u << 28) - 1;
inline uint32_t pixel_id(const DrawItem& item) { return (uint32_t(item.kind) << 28) | (item.id + 1); }

// Supplies the geometry of a draw item that is not resident on the GPU. The pointer must stay
// valid until the provider is called again. Returning nullptr skips the item (data not ready).
using MeshProvider = std::function<const Mesh*(const DrawItem&)>;

// Supplies base-colour texture `index` (Mesh::texture) decoded, its larger side at most
// `max_side` texels (decode_texture does that), when a mesh that samples it is drawn and the
// renderer does not hold it; nullopt draws the mesh untextured.
using TextureSource = std::function<std::optional<Texture>(uint32_t index, uint32_t max_side)>;

// A far-field image on a face of a view cell's bounding box (stratified rendering, seed 002
// §3.1.2): the quad origin + s·u + t·v, s, t in [0, 1], showing `color` with (s, t) = (0, 0) at
// its first (bottom) row's first pixel. Texels with alpha < 128 show nothing (no far geometry
// there). `ids`, if given (same size), is written to the id buffer (object id + 1 per texel, 0
// for none), so the objects the face shows count as drawn; without it the face writes
// pixel_id({id, 0, ..., kFarFace}). The images must stay valid during render(); the renderer
// keeps GL copies keyed by `id` (so one id must always show the same images). A face with
// `opacity` < 1 is blended over what is drawn before it (colour · opacity + what is there ·
// (1 − opacity)) and leaves the id buffer alone: a face fading out after a crossing.
struct FarFace {
  uint32_t id = 0;
  Vec3 origin{0.0f};
  Vec3 u{0.0f};
  Vec3 v{0.0f};
  const Image* color = nullptr;
  const IdImage* ids = nullptr;
  float opacity = 1.0f;  // in [0, 1]
};

// A world-space segment for overlays: frustums and boxes in a bird's-eye view.
struct LineSegment {
  Vec3 a{0.0f};
  Vec3 b{0.0f};
  Rgba8 color = rgba8(255, 255, 0);
};

// Appends the twelve edges of `box` to `out`.
void append_box_lines(const Aabb& box, Rgba8 color, std::vector<LineSegment>& out);

struct RenderStats {
  uint64_t triangles = 0;
  uint64_t objects = 0;
  uint64_t gpu_hits = 0;
  uint64_t gpu_misses = 0;
  uint64_t uploaded_bytes = 0;
  uint64_t gpu_resident_bytes = 0;  // after the frame; never above the budget
  double ms = 0.0;                  // wall time including glFinish
};

struct RenderSettings;
// Fits the backdrop to a world: the ground at its lowest point, the grid a power of ten near a
// tenth of its larger horizontal extent E, at most 10 m (10 m for a city, 10 cm for a 1 m
// scan), the haze at 30 E.
void fit_backdrop(RenderSettings& settings, const Aabb& world_bounds);

struct RenderSettings {
  int width = 640;
  int height = 480;
  Rgba8 background = rgba8(178, 204, 230);
  // Draw a backdrop instead of the flat background: a sky gradient above the horizon and a
  // ground plane (y = ground_y) with a faint grid of ground_grid metres below it, so a walker
  // sees where the ground is. Colour only: the id target stays background and depth is untouched.
  bool backdrop = false;
  float ground_y = 0.0f;
  float ground_grid = 10.0f;
  float ground_haze = 3000.0f;  // distance at which the ground fades into the sky, metres
  // GPU-side vertex and index buffers are cached under this many bytes (LRU). A mesh larger
  // than the whole budget is drawn from a transient buffer and not kept.
  uint64_t gpu_budget_bytes = 512ull << 20;
  // Far-face textures are kept under this many bytes (LRU), apart from the meshes.
  uint64_t far_face_budget_bytes = 64ull << 20;
  // The share of gpu_budget_bytes that base-colour textures take once a TextureSource is set
  // (the meshes keep the rest, so the two together stay within gpu_budget_bytes), at most
  // max_texture_budget_bytes (mipmapped RGBA8, LRU).
  double texture_share = 0.25;
  uint64_t max_texture_budget_bytes = 128ull << 20;
};

// Triangles queued between waits for the GPU. Mesa's llvmpipe bins every triangle queued since
// the last finish into per-tile command lists and keeps that memory afterwards: measured at about
// 240 MiB per million long thin triangles, so a frame's driver memory would grow with the world.
// Waiting every kDriverBatchTriangles bounds it by what one batch needs, which the baseline's
// warm-up reaches (cellwalk/runtime/run_budget.hpp); a larger mesh is drawn in index ranges.
inline constexpr uint32_t kDriverBatchTriangles = 1u << 16;

// REQUIRES: a current GlContext (or window context) on the calling thread for its lifetime.
class Renderer {
 public:
  explicit Renderer(const RenderSettings& settings);
  ~Renderer();

  // Renders items into the offscreen targets and waits for the GPU, so the time is real.
  // Items are drawn in ascending (object, lod) order whatever their order in `items`, so any
  // subset of a list renders its objects' pixels exactly as the full list does.
  // Far faces are drawn first, as background: no depth test and no depth writes, so near
  // geometry that sticks out past its box is never hidden by them (digest 002 §3.6).
  RenderStats render(const Camera& camera, std::span<const DrawItem> items,
                     const MeshProvider& provider, std::span<const FarFace> far_faces = {});

  // Where the textures meshes sample come from (a world's, world_textures()). Until one is set
  // meshes are drawn untextured and the whole GPU budget holds meshes; setting one gives
  // textures their share of it (RenderSettings::texture_share).
  void set_texture_source(TextureSource source);

  // Overlays, drawn over the colour target of the last render() (so read_color() and present()
  // include them) without depth test; the id target is left as render() wrote it. Call them
  // after render(), which clears everything. One-pixel lines (all core profiles guarantee).
  void draw_lines(const Camera& camera, std::span<const LineSegment> segments);
  // ASCII text in stb_easy_font's glyphs (about 7 px tall on 12 px lines at scale 1, times
  // `scale`); (x, y) is the top-left corner in pixels from the image's top-left; '\n' starts
  // a new line, and lines are wrapped at spaces to stay inside the image. With `panel`, the
  // text lies on an opaque rectangle of that colour (a 4-pixel margin around it), so it stays
  // readable over any scene.
  void draw_text(float x, float y, std::string_view text, Rgba8 color, float scale = 1.0f,
                 std::optional<Rgba8> panel = std::nullopt);

  Image read_color() const;
  IdImage read_ids() const;
  // The depth target: window depth in [0, 1] per pixel (1 where nothing was drawn), rows bottom-up.
  std::vector<float> read_depth() const;
  // Copies the colour target to the default framebuffer (the window) at its size.
  void present(int window_width, int window_height) const;

  const RenderSettings& settings() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
