// A CPU cube depth buffer around one point with conservative rasterisation: occluders are
// underestimated (a pixel takes an occluder's depth only when the occluder covers all of it,
// and then its farthest entry depth over the pixel), occludees overestimated (every pixel
// their box may touch, at their nearest depth).
// Seed: 001 vLOD §5.2.2 (shrunk occluders rendered to depth from one point, occludees tested
// against it; conservative rasterisation by alpha cut-off, here exact for boxes) and 000 HDoV
// thesis §5.5.2 (the six faces of a cube around the viewpoint).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "cellwalk/geometry.hpp"

namespace cellwalk::visibility {

// Face f looks along axis f / 2, positive for even f. Depth is the distance along that axis.
// Thread-safety: none; one buffer per thread.
class CubeDepthBuffer {
 public:
  // REQUIRES: resolution >= 1 (pixels per face side).
  CubeDepthBuffer(const Vec3& eye, int resolution);

  // Limits later rendering to the pixels hidden(box) reads, summed over calls: rendering is
  // the cost, and only pixels some occludee is tested against can change an answer. Without
  // any call, every pixel is rendered. REQUIRES: no occluder rendered yet.
  void demand(const Aabb& box);

  // Renders a box occluder: after the call, every ray from the eye through a pixel the box
  // covers entirely meets the box at a depth no greater than the pixel's.
  void add_occluder(const Aabb& box);

  // Renders `box` shrunk for a box cell centred on the eye with half-extents `half`, per face
  // along the face's two lateral axes only, by half + half_depth · |slope| (the largest slope
  // over each pixel), and only in faces where the box lies wholly beyond the cell. Whatever
  // this hides from the eye, the unshrunk box hides from every point of the cell: a segment
  // from a cell point to the occludee crosses the box's depth at a lateral offset of at most
  // that much from the eye's ray (derivation in docs/conservative-visibility.md).
  void add_occluder_for_cell(const Aabb& box, const Vec3& half);

  // True only when every ray from the eye that meets `box` meets an occluder rendered before
  // at a smaller depth. False when the box contains the eye.
  bool hidden(const Aabb& box) const;

  // False only when rendering any occluder inside `box` (add_occluder or add_occluder_for_cell
  // of a box it contains) would change no wanted pixel: every tile its projection touches has
  // no wanted pixel deeper than the box's nearest depth in that face. Lets a front-to-back walk
  // skip whole groups of occluders without changing the buffer.
  bool may_lower(const Aabb& box) const;

  // Fraction of the sphere's pixels with an occluder, for reports.
  double covered_fraction() const;

  // Entry and exit depths of the rays through a pixel's two edges into one slab (add_to_face),
  // valid for the add_to_face call whose stamp it carries.
  struct Span {
    double enter, exit;
    uint64_t stamp;
  };

 private:
  static constexpr int kTile = 8;  // pixels per side of a tile

  glm::dvec3 eye_;
  int n_;
  int tiles_;                     // per face side
  std::vector<float> depth_;      // 6 faces of n × n, +inf where no occluder covers the pixel
  std::vector<uint8_t> demand_;   // empty (all pixels) or 1 per pixel hidden() may read
  // Per tile, the largest depth of its wanted pixels (-inf if none): an occluder no nearer
  // than that cannot improve the tile, so whole tiles are skipped.
  std::vector<float> tile_max_;
  std::vector<Span> columns_, rows_;  // add_to_face's scratch, per pixel column and row
  uint64_t stamp_ = 0;                // add_to_face calls so far

  bool wanted(int face, int i, int j) const {
    return demand_.empty() || demand_[(size_t(face) * n_ + j) * n_ + i] != 0;
  }
  size_t tile_index(int face, int ti, int tj) const { return (size_t(face) * tiles_ + tj) * tiles_ + ti; }
  void update_tile(int face, int ti, int tj);

  struct PixelRect {
    int i0, i1, j0, j1;  // inclusive
    double near;         // the depth the box's points in the face lie at or beyond
  };
  // The pixels the part of an occludee box (relative to the eye) inside a face's pyramid may
  // touch; nullopt when no point of the box lies in the pyramid.
  std::optional<PixelRect> occludee_pixels(int face, const glm::dvec3& lo, const glm::dvec3& hi) const;
  void add_to_face(int face, const glm::dvec3& lo, const glm::dvec3& hi, const glm::dvec3& half);
};

}  // namespace cellwalk::visibility
