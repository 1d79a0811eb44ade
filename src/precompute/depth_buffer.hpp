// A CPU cube depth buffer around one point with conservative rasterisation: occluders are
// underestimated (a pixel takes an occluder's depth only when the occluder covers all of it,
// and then its farthest entry depth over the pixel), occludees overestimated (every pixel
// their box may touch, at their nearest depth).
// Seed: 001 vLOD §5.2.2 (shrunk occluders rendered to depth from one point, occludees tested
// against it; conservative rasterisation by alpha cut-off, here exact for boxes) and 000 HDoV
// thesis §5.5.2 (the six faces of a cube around the viewpoint).
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "cellwalk/core/geometry.hpp"

namespace cellwalk::visibility {

// Face f looks along axis f / 2, positive for even f. Depth is the distance along that axis.
// Thread-safety: none; one buffer per thread.
class CubeDepthBuffer {
 public:
  // REQUIRES: resolution >= 1 (pixels per face side).
  CubeDepthBuffer(const Vec3& eye, int resolution);

  // Makes this buffer answer as a new one around `eye` would, keeping its storage: a cell's
  // refinement needs up to 85 buffers, and clearing 6 whole faces for each cost more than
  // what they are used for. Only the tiles used since are cleared, when first touched.
  void aim(const Vec3& eye);

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

  // A pixel's depth: the nearest occluder depth rendered there, +inf where none. Pixels not
  // wanted by demand() are not rendered. REQUIRES: 0 <= face < 6, 0 <= i, j < resolution.
  float depth(int face, int i, int j) const;

  // Entry and exit depths of the rays through a pixel's two edges into one slab (add_to_face),
  // valid for the add_to_face call whose stamp it carries.
  struct Span {
    double enter, exit;
    uint64_t stamp;
  };

 private:
  static constexpr int kTile = 8;   // pixels per side of a tile
  static constexpr int kGroup = 8;  // tiles per side of a group

  glm::dvec3 eye_;
  int n_;
  int tiles_;                     // per face side
  // 6 faces of n × n, +inf where no occluder covers the pixel. Valid in live tiles only.
  std::vector<float> depth_;
  std::vector<uint8_t> demand_;   // 1 per pixel hidden() may read; live tiles, demanding_ only
  bool demanding_ = false;        // demand() was called since aim(): else every pixel is wanted
  // Per tile, the largest depth of its wanted pixels (-inf if none): an occluder no nearer
  // than that cannot improve the tile, so whole tiles are skipped. Valid in every tile.
  std::vector<float> tile_max_;
  int groups_;  // per face side
  // Per group of kGroup × kGroup tiles, the largest of their tile_max_: the same skipping for
  // whole groups, so a large box's footprint costs no more than a few reads where it is hidden.
  std::vector<float> group_max_;
  // A tile is live when its tile_epoch_ is epoch_: its pixels were cleared since aim(). A tile
  // not live reads as all +inf and, while demanding_, unwanted.
  std::vector<uint32_t> tile_epoch_;
  uint32_t epoch_ = 0;
  std::vector<Span> columns_, rows_;  // add_to_face's scratch, per pixel column and row
  uint64_t stamp_ = 0;                // add_to_face calls so far

  // REQUIRES: the pixel's tile is live.
  bool wanted(int face, int i, int j) const {
    return !demanding_ || demand_[(size_t(face) * n_ + j) * n_ + i] != 0;
  }
  size_t tile_index(int face, int ti, int tj) const { return (size_t(face) * tiles_ + tj) * tiles_ + ti; }
  size_t group_index(int face, int ti, int tj) const {
    return (size_t(face) * groups_ + tj / kGroup) * groups_ + ti / kGroup;
  }
  void set_tile_max(int face, int ti, int tj, float largest);
  void fill_maxima(float value);
  // Calls visit(ti, tj) for each tile meeting the pixel rectangle [i0, i1] × [j0, j1] of the
  // face whose largest wanted depth exceeds `above`, until visit returns true; returns
  // whether it did. visit may lower the tiles' maxima (set_tile_max).
  template <class Visit>
  bool tiles_deeper_than(int face, int i0, int i1, int j0, int j1, double above, Visit&& visit) const;
  bool live(int face, int ti, int tj) const { return tile_epoch_[tile_index(face, ti, tj)] == epoch_; }
  void make_live(int face, int ti, int tj);  // clears the tile's pixels if it is not live
  void update_tile(int face, int ti, int tj);
  // One past the last pixel of tile t along a face side.
  int tile_end(int t) const { return std::min(n_, (t + 1) * kTile); }

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
