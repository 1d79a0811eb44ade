// Stratified rendering (seed 002, Xiong 1996) §3.1.2 (digest 002 §3.6): the far field of a
// viewcell, every object that is not near drawn from the cell centre C onto the faces of its
// bounding box. Each face is a 90° × 90° perspective view from C with the face as image plane (a
// cube-map face drawn at its true distance b/2, which the error analysis assumes); its colour,
// the id of the object each texel shows, and the texel's distance from C are kept.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "cellwalk/core/camera.hpp"
#include "cellwalk/render/image.hpp"
#include "cellwalk/render/renderer.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk::stratified {

// Faces in the order −Z, −X, +Z, +X (the four vertical faces), +Y, −Y.
constexpr int kFaceCount = 6;
// 8·R² bytes of textures a face (colour and ids) must fit the renderer's far-face budget.
constexpr int kMaxFaceResolution = 2048;

// The camera that sees face `face` of the box of side b around c: at c, looking out through
// the face's centre, 90° square, near plane just inside the face.
Camera face_camera(const Vec3& c, float b, int face, float far_plane);
// The face as the renderer draws it: origin + s·u + t·v, (s, t) = (0, 0) at the image's bottom
// left as face_camera sees it.
FarFace face_quad(const Vec3& c, float b, int face, uint32_t id);

// One baked face. depth: per texel the distance from C along the view ray to the far surface
// (0 where nothing far is seen).
struct FaceImage {
  int face = 0;
  Image color;    // alpha 0 where nothing far is seen
  IdImage ids;    // object id + 1, 0 for none
  std::vector<float> depth;
};

// A cell's far field: its non-empty faces, in face order (empty faces are skipped, §3.6).
struct CellFarField {
  std::vector<FaceImage> faces;
};

// The far field's angular error seen from `camera` [ours; the thesis only bounds it, §2.3]: the
// largest angle, over the baked texels inside the camera's frustum, between where the far point
// really is (P = c + its view ray · depth; at infinite depth, the ray's direction) and where the
// face shows it (Q, the texel's centre on the face), both seen from the eye. Radians; 0 when no
// far texel is in view.
double far_field_angle(const CellFarField& field, const Vec3& c, float b, const Camera& camera);

// How far faces are drawn.
struct BakeSettings {
  int resolution = 512;  // texels per face side
  // Each far object at the coarsest level whose error, seen from C, covers less than this many
  // texels anywhere on the face [ours: the thesis draws the full model; a level under half a
  // texel draws the same image, and at city scale it makes baking many times cheaper]. 0 draws
  // every object at level 0, as the thesis does.
  float max_texels = 0.5f;
  uint64_t gpu_budget_bytes = 256ull << 20;
};

// Renders far fields with a headless GL context of its own, made on the constructing thread;
// every call must come from that thread. Objects are decoded from the world on demand and kept
// in the renderer's GPU cache.
class FarFieldBaker {
 public:
  // Throws Error for a resolution outside [1, kMaxFaceResolution], a negative or non-finite
  // max_texels, or when no headless context can be made.
  FarFieldBaker(const World& world, const BakeSettings& settings);
  ~FarFieldBaker();
  int resolution() const;
  // The far field of a cell centred at c with box side b: every object not in `near` (ascending
  // ids) whose box meets a face's frustum, drawn from c.
  CellFarField bake(const Vec3& c, float b, std::span<const ObjectId> near);
  // Triangles drawn by every bake so far (what the level choice saves).
  uint64_t triangles_drawn() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk::stratified
