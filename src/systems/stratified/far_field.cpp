// Stratified thesis §3.1.2, Fig. 3-3, §5.2.3 (digest 002 §3.6): far-field baking, every non-near
// object rendered from the cell centre onto the box faces.
#include "cellwalk/strategy/world_textures.hpp"
#include "cellwalk/systems/stratified/far_field.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/level_choice.hpp"

namespace cellwalk::stratified {
namespace {

// (yaw, pitch) of each face's view, in kFaceCount order (−Z, −X, +Z, +X, +Y, −Y).
constexpr float kFaceAngles[kFaceCount][2] = {{0, 0}, {90, 0}, {180, 0}, {270, 0}, {0, 90}, {0, -90}};

// Transparent clear: texels no far object covers keep alpha 0, and show nothing at run time.
constexpr Rgba8 kEmpty = 0;

}  // namespace

Camera face_camera(const Vec3& c, float b, int face, float far_plane) {
  Camera camera;
  camera.position = c;
  camera.yaw_deg = kFaceAngles[face][0];
  camera.pitch_deg = kFaceAngles[face][1];
  camera.fov_y_deg = 90.0f;
  camera.aspect = 1.0f;
  // Every far object lies outside the box, at least b/2 along the face's axis: a near plane just
  // inside the face clips nothing far and keeps depth precise.
  camera.near_plane = 0.49f * b;
  camera.far_plane = far_plane;
  return camera;
}

FarFace face_quad(const Vec3& c, float b, int face, uint32_t id) {
  const Camera camera = face_camera(c, b, face, 1.0f);
  const float h = 0.5f * b;
  const Vec3 f = camera.forward(), r = camera.right(), u = camera.up();
  FarFace quad;
  quad.id = id;
  quad.origin = c + h * (f - r - u);
  quad.u = 2.0f * h * r;
  quad.v = 2.0f * h * u;
  return quad;
}

double far_field_angle(const CellFarField& field, const Vec3& c, float b, const Camera& camera) {
  const Frustum frustum(camera);
  const glm::dvec3 eye(camera.position);
  double worst = 0.0;
  for (const FaceImage& f : field.faces) {
    const Camera face = face_camera(c, b, f.face, 1.0f);
    const Vec3 fwd = face.forward(), right = face.right(), up = face.up();
    const int res = f.color.width;
    for (int j = 0; j < res; ++j)
      for (int i = 0; i < res; ++i) {
        const float depth = f.depth[size_t(j) * res + i];
        if (depth <= 0.0f) continue;
        const float x = (2.0f * i + 1.0f) / res - 1.0f, y = (2.0f * j + 1.0f) / res - 1.0f;
        const Vec3 ray = fwd + x * right + y * up;  // reaches the face at t = b/2
        const Vec3 q = c + 0.5f * b * ray;
        Aabb point;
        point.extend(q);
        if (!frustum.intersects(point)) continue;
        const glm::dvec3 to_q = glm::dvec3(q) - eye;
        // At infinite depth the far point is seen along the ray itself, from any eye.
        const glm::dvec3 to_p = std::isinf(depth) ? glm::normalize(glm::dvec3(ray))
                                                  : glm::dvec3(c) + glm::normalize(glm::dvec3(ray)) * double(depth) - eye;
        worst = std::max(worst, std::atan2(glm::length(glm::cross(to_q, to_p)), glm::dot(to_q, to_p)));
      }
  }
  return worst;
}

struct FarFieldBaker::Impl {
  const World& world;
  int resolution;
  float max_texels;
  Lens lens;  // a face's: 90° square, `resolution` texels high
  std::unique_ptr<GlContext> context;
  std::unique_ptr<Renderer> renderer;
  Mesh mesh;  // the provider's last decoded mesh: valid until the next call
  std::vector<DrawItem> items;
  float far_plane;
  uint64_t triangles_drawn = 0;

  Impl(const World& w, const BakeSettings& s) : world(w), resolution(s.resolution), max_texels(s.max_texels) {
    const int res = s.resolution;
    if (res < 1 || res > kMaxFaceResolution)
      fail("stratify", "face resolution " + std::to_string(res) + " must lie in [1, " + std::to_string(kMaxFaceResolution) + "]");
    if (!(max_texels >= 0.0f) || !std::isfinite(max_texels))
      fail("stratify", "the far field's level error bound (" + std::to_string(max_texels) + " texels) must be 0 or more");
    lens = {glm::radians(90.0f), 1.0f, float(res)};
    context = GlContext::headless();
    RenderSettings settings;
    settings.width = settings.height = res;
    settings.background = kEmpty;
    settings.gpu_budget_bytes = s.gpu_budget_bytes;
    renderer = std::make_unique<Renderer>(settings);
    use_world_textures(*renderer, world);  // far faces show what near geometry shows
    far_plane = 2.0f * glm::length(world.info().bounds.size()) + 10.0f;
  }

  // The texel distances from c along each view ray, from window depth (perspective: the eye-space
  // depth is n·f / (f − d·(f − n)), and a ray through texel (x, y) is √(1 + x² + y²) times longer).
  std::vector<float> distances(const std::vector<float>& window_depth, const Camera& camera) const {
    const float n = camera.near_plane, f = camera.far_plane;
    std::vector<float> out(window_depth.size(), 0.0f);
    for (int j = 0; j < resolution; ++j)
      for (int i = 0; i < resolution; ++i) {
        const size_t k = size_t(j) * resolution + i;
        const float d = window_depth[k];
        if (d >= 1.0f) continue;
        const float x = (2.0f * i + 1.0f) / resolution - 1.0f, y = (2.0f * j + 1.0f) / resolution - 1.0f;
        out[k] = n * f / (f - d * (f - n)) * std::sqrt(1.0f + x * x + y * y);
      }
    return out;
  }

  // The face's image, or nullopt when no far object is in its frustum or none covers a texel.
  std::optional<FaceImage> bake_face(const Vec3& c, float b, int face, std::span<const ObjectId> near) {
    const Camera camera = face_camera(c, b, face, far_plane);
    const Frustum frustum(camera);
    items.clear();
    size_t next_near = 0;
    for (ObjectId id = 0; id < world.object_count(); ++id) {
      while (next_near < near.size() && near[next_near] < id) ++next_near;
      if (next_near < near.size() && near[next_near] == id) continue;
      if (!frustum.intersects(world.object(id).bounds)) continue;
      const uint32_t level = max_texels > 0.0f ? level_for_screen_error(world, id, c, lens, max_texels) : 0;
      items.push_back({id, level, world.object(id).color});
    }
    if (items.empty()) return std::nullopt;
    triangles_drawn += renderer->render(camera, items, [this](const DrawItem& item) -> const Mesh* {
      mesh = world.decode_level(item.id, item.lod, world.read_level(item.id, item.lod));
      return &mesh;
    }).triangles;
    FaceImage image;
    image.face = face;
    image.ids = renderer->read_ids();
    bool any = false;
    for (const uint32_t id : image.ids.ids) any |= id != kBackgroundId;
    if (!any) return std::nullopt;
    image.color = renderer->read_color();
    image.depth = distances(renderer->read_depth(), camera);
    return image;
  }
};

FarFieldBaker::FarFieldBaker(const World& world, const BakeSettings& settings)
    : impl_(std::make_unique<Impl>(world, settings)) {}

FarFieldBaker::~FarFieldBaker() = default;

int FarFieldBaker::resolution() const { return impl_->resolution; }

uint64_t FarFieldBaker::triangles_drawn() const { return impl_->triangles_drawn; }

CellFarField FarFieldBaker::bake(const Vec3& c, float b, std::span<const ObjectId> near) {
  CellFarField field;
  for (int face = 0; face < kFaceCount; ++face)
    if (std::optional<FaceImage> image = impl_->bake_face(c, b, face, near)) field.faces.push_back(std::move(*image));
  return field;
}

}  // namespace cellwalk::stratified
