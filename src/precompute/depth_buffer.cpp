// A CPU cube depth buffer with conservative rasterisation of boxes.
// Seed: 001 vLOD §5.2.2 (shrunk occluders to depth, occludees tested against it, conservative
// rasterisation) and 000 HDoV thesis §5.5.2 (cube of six faces around the viewpoint).
#include "precompute/depth_buffer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cellwalk::visibility {
namespace {

constexpr float kFar = std::numeric_limits<float>::infinity();

struct FaceAxes {
  int a, b, c;  // depth axis, u axis, w axis
  double sign;  // of the depth axis
};

FaceAxes axes_of(int face) {
  const int a = face / 2;
  return {a, (a + 1) % 3, (a + 2) % 3, face % 2 == 0 ? 1.0 : -1.0};
}

// The box, relative to the eye, in a face's frame: depth range and the (u, w) extent of its
// central projection, for the part of it at depth >= near (> 0).
struct Footprint {
  double u0, u1, w0, w1;
};

Footprint project(const FaceAxes& f, const glm::dvec3& lo, const glm::dvec3& hi, double near,
                  double far) {
  Footprint fp{std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
               std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest()};
  for (double z : {near, far})
    for (double u : {lo[f.b], hi[f.b]})
      for (double w : {lo[f.c], hi[f.c]}) {
        fp.u0 = std::min(fp.u0, u / z), fp.u1 = std::max(fp.u1, u / z);
        fp.w0 = std::min(fp.w0, w / z), fp.w1 = std::max(fp.w1, w / z);
      }
  return fp;
}

// One lateral slab lo <= s·z <= hi against the rays of slopes s0 and s1 (depth z the ray's
// parameter): the larger of their entry depths and the smaller of their exit depths; an entry
// of +inf when either ray misses the slab (or it is empty).
CubeDepthBuffer::Span slab_span(double lo, double hi, double s0, double s1) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (lo > hi) return {kInf, -kInf, 0};
  CubeDepthBuffer::Span out{-kInf, kInf, 0};
  for (double s : {s0, s1}) {
    if (s == 0.0) {
      if (lo > 0.0 || hi < 0.0) return {kInf, -kInf, 0};
      continue;
    }
    double enter = lo / s, exit = hi / s;
    if (enter > exit) std::swap(enter, exit);
    out.enter = std::max(out.enter, enter);
    out.exit = std::min(out.exit, exit);
  }
  return out;
}

// How far the interval [lo, hi] lies from 0 (0 when it holds 0).
double lateral_gap(double lo, double hi) { return std::max({0.0, lo, -hi}); }

double depth_range(const FaceAxes& f, const glm::dvec3& lo, const glm::dvec3& hi, bool far) {
  return f.sign > 0 ? (far ? hi[f.a] : lo[f.a]) : (far ? -lo[f.a] : -hi[f.a]);
}

// Points of the box seen in a face lie at depth >= their max-norm distance from the eye,
// hence >= the box's: clipping there keeps the projection finite. <= 0: the box holds the eye.
double max_norm_distance(const glm::dvec3& lo, const glm::dvec3& hi) {
  double distance = 0.0;
  for (int a = 0; a < 3; ++a) distance = std::max({distance, lo[a], -hi[a]});
  return distance;
}

}  // namespace

CubeDepthBuffer::CubeDepthBuffer(const Vec3& eye, int resolution)
    : n_(resolution),
      tiles_((resolution + kTile - 1) / kTile),
      depth_(size_t(6) * resolution * resolution),
      demand_(size_t(6) * resolution * resolution),
      tile_max_(size_t(6) * tiles_ * tiles_),
      groups_((tiles_ + kGroup - 1) / kGroup),
      group_max_(size_t(6) * groups_ * groups_),
      tile_epoch_(size_t(6) * tiles_ * tiles_, 0),
      columns_(size_t(resolution)),
      rows_(size_t(resolution)) {
  aim(eye);
}

void CubeDepthBuffer::aim(const Vec3& eye) {
  eye_ = eye;
  demanding_ = false;
  fill_maxima(kFar);  // every pixel wanted and empty
  if (++epoch_ == 0) {  // the stamps wrapped: none may look live by chance
    std::fill(tile_epoch_.begin(), tile_epoch_.end(), 0u);
    epoch_ = 1;
  }
}

void CubeDepthBuffer::fill_maxima(float value) {
  std::fill(tile_max_.begin(), tile_max_.end(), value);
  std::fill(group_max_.begin(), group_max_.end(), value);
}

// A group's largest depth changes only when it came from this tile. Raising a tile (demand)
// raises its group; lowering one (rendering) may lower it, found by reading the group again.
void CubeDepthBuffer::set_tile_max(int face, int ti, int tj, float largest) {
  float& tile = tile_max_[tile_index(face, ti, tj)];
  float& group = group_max_[group_index(face, ti, tj)];
  const float old = tile;
  tile = largest;
  if (largest >= group) {
    group = largest;
    return;
  }
  if (old < group) return;
  float top = -kFar;
  const int gi = ti / kGroup * kGroup, gj = tj / kGroup * kGroup;
  for (int j = gj; j < std::min(tiles_, gj + kGroup); ++j)
    for (int i = gi; i < std::min(tiles_, gi + kGroup); ++i) top = std::max(top, tile_max_[tile_index(face, i, j)]);
  group = top;
}

template <class Visit>
bool CubeDepthBuffer::tiles_deeper_than(int face, int i0, int i1, int j0, int j1, double above,
                                        Visit&& visit) const {
  const int ti0 = i0 / kTile, ti1 = i1 / kTile, tj0 = j0 / kTile, tj1 = j1 / kTile;
  for (int gj = tj0 / kGroup; gj <= tj1 / kGroup; ++gj)
    for (int gi = ti0 / kGroup; gi <= ti1 / kGroup; ++gi) {
      if (!(double(group_max_[(size_t(face) * groups_ + gj) * groups_ + gi]) > above)) continue;
      for (int tj = std::max(tj0, gj * kGroup); tj <= std::min(tj1, gj * kGroup + kGroup - 1); ++tj)
        for (int ti = std::max(ti0, gi * kGroup); ti <= std::min(ti1, gi * kGroup + kGroup - 1); ++ti)
          if (double(tile_max_[tile_index(face, ti, tj)]) > above && visit(ti, tj)) return true;
    }
  return false;
}

void CubeDepthBuffer::make_live(int face, int ti, int tj) {
  uint32_t& stamp = tile_epoch_[tile_index(face, ti, tj)];
  if (stamp == epoch_) return;
  stamp = epoch_;
  const int i0 = ti * kTile, width = tile_end(ti) - i0;
  for (int j = tj * kTile; j < tile_end(tj); ++j) {
    const size_t row = (size_t(face) * n_ + j) * n_ + i0;
    std::fill_n(depth_.begin() + ptrdiff_t(row), width, kFar);
    std::fill_n(demand_.begin() + ptrdiff_t(row), width, uint8_t(0));
  }
}

void CubeDepthBuffer::add_occluder(const Aabb& box) { add_occluder_for_cell(box, Vec3(0.0f)); }

void CubeDepthBuffer::add_occluder_for_cell(const Aabb& box, const Vec3& half) {
  const glm::dvec3 lo = glm::dvec3(box.min) - eye_, hi = glm::dvec3(box.max) - eye_;
  for (int face = 0; face < 6; ++face) add_to_face(face, lo, hi, glm::dvec3(half));
}

// Per pixel, the box eroded laterally by the pixel's bound (none for a point cell). A pixel
// is covered when the rays through its 4 corners meet that box: the directions that meet a
// convex set form a convex set. Its depth is the largest of the 4 entry depths: each slab's
// entry depth over the pixel is monotone in u alone or w alone (or constant, or <= 0), so its
// maximum over the pixel's rectangle lies at a corner, and so does the maximum of their
// maximum.
//
// The 4 slab tests per pixel are factored: a corner ray (u, w) meets the box when
// max(0, enter_a, enter_b(u), enter_c(w)) <= min(exit_a, exit_b(u), exit_c(w)), and the lateral
// erosion of slab b depends on the pixel's column only (c on its row). Over the 4 corners
// that is: each term of one slab against the other slabs' terms at their worst corner (the
// largest entry, the smallest exit of the pixel's two edges); a slab against itself at one
// ray always holds. So columns and rows are computed once per face, and the pixels get the
// same coverage and the same depth as with 4 slab tests each.
void CubeDepthBuffer::add_to_face(int face, const glm::dvec3& lo, const glm::dvec3& hi,
                                  const glm::dvec3& half) {
  const FaceAxes f = axes_of(face);
  const double near = depth_range(f, lo, hi, false), far = depth_range(f, lo, hi, true);
  const bool point = half == glm::dvec3(0.0);
  if (far <= 0.0 || (!point && near < half[f.a])) return;  // the cell must lie before the box
  // A ray of the face meets the box only at points as deep as they are far from the depth axis
  // (|u|, |w| <= 1): none when the box ends before that, and the rest lie at depth >= `front`.
  const double front = std::max({near, lateral_gap(lo[f.b], hi[f.b]), lateral_gap(lo[f.c], hi[f.c])});
  if (far < front) return;
  Footprint fp{-1.0, 1.0, -1.0, 1.0};  // a box across the eye's plane may cover it all
  if (front > 0.0) fp = project(f, lo, hi, front, far);
  const double scale = 0.5 * n_;
  // Footprints of boxes just beyond the eye's plane reach far outside the face: clamp in
  // double before converting, so the int conversion stays defined.
  const auto pixel = [&](double t) { return std::clamp((t + 1.0) * scale, 0.0, double(n_)); };
  const int i0 = int(std::ceil(pixel(fp.u0)));
  const int i1 = int(std::floor(pixel(fp.u1)));
  const int j0 = int(std::ceil(pixel(fp.w0)));
  const int j1 = int(std::floor(pixel(fp.w1)));
  if (i0 >= i1 || j0 >= j1) return;
  // The depth slab (not eroded): dir's depth component is the face's sign.
  double enter_a = lo[f.a] / f.sign, exit_a = hi[f.a] / f.sign;
  if (enter_a > exit_a) std::swap(enter_a, exit_a);
  const double base = std::max(0.0, enter_a);
  // Lateral slabs per column (b) and row (c), computed when a pixel first needs them: eroded
  // by the pixel's bound, then the larger entry and smaller exit over the pixel's two edges.
  ++stamp_;
  const auto span = [&](int axis, int k, std::vector<Span>& spans) -> const Span& {
    Span& out = spans[size_t(k)];
    if (out.stamp != stamp_) {
      const double s0 = k / scale - 1.0, s1 = (k + 1) / scale - 1.0;
      const double erode = half[axis] + half[f.a] * std::max(std::abs(s0), std::abs(s1));
      out = slab_span(lo[axis] + erode, hi[axis] - erode, s0, s1);
      out.stamp = stamp_;
    }
    return out;
  };
  const double skip = std::max(front, 0.0);  // pixels at or nearer than this gain nothing
  float* pixels = depth_.data() + size_t(face) * n_ * n_;
  // Pixels with depth <= skip are not written (the tile is skipped where all wanted ones are).
  tiles_deeper_than(face, i0, i1 - 1, j0, j1 - 1, skip, [&](int ti, int tj) {
    make_live(face, ti, tj);  // not live only while every pixel is wanted
    bool wrote = false;
    for (int j = std::max(j0, tj * kTile); j < std::min(j1, (tj + 1) * kTile); ++j) {
      const Span* row = nullptr;
      for (int i = std::max(i0, ti * kTile); i < std::min(i1, (ti + 1) * kTile); ++i) {
        float& pixel = pixels[size_t(j) * n_ + i];
        if (double(pixel) <= skip || !wanted(face, i, j)) continue;
        if (!row) {
          row = &span(f.c, j, rows_);
          if (!(base <= row->exit && row->enter <= exit_a)) break;
        }
        const Span& column = span(f.b, i, columns_);
        if (!(base <= column.exit && column.enter <= exit_a && column.enter <= row->exit && row->enter <= column.exit))
          continue;
        const double d = std::max({base, column.enter, row->enter});
        // Round up: the stored depth may only exceed the occluder's.
        pixel = std::min(pixel, std::nextafter(float(d), kFar));
        wrote = true;
      }
    }
    if (wrote) update_tile(face, ti, tj);
    return false;
  });
}

void CubeDepthBuffer::update_tile(int face, int ti, int tj) {
  float largest = -kFar;
  for (int j = tj * kTile; j < tile_end(tj); ++j)
    for (int i = ti * kTile; i < tile_end(ti); ++i)
      if (wanted(face, i, j)) largest = std::max(largest, depth_[(size_t(face) * n_ + j) * n_ + i]);
  set_tile_max(face, ti, tj, largest);
}

std::optional<CubeDepthBuffer::PixelRect> CubeDepthBuffer::occludee_pixels(int face, const glm::dvec3& lo,
                                                                          const glm::dvec3& hi) const {
  const FaceAxes f = axes_of(face);
  const double distance = max_norm_distance(lo, hi);
  const double far = depth_range(f, lo, hi, true);
  if (far < distance) return std::nullopt;  // no point of the box in this face's pyramid
  const double near = std::max(depth_range(f, lo, hi, false), distance);
  Footprint fp = project(f, lo, hi, near, far);
  constexpr double kPad = 1e-9;  // projection rounding: overestimate the occludee
  fp.u0 -= kPad, fp.w0 -= kPad, fp.u1 += kPad, fp.w1 += kPad;
  if (fp.u0 > 1.0 || fp.w0 > 1.0 || fp.u1 < -1.0 || fp.w1 < -1.0) return std::nullopt;
  const double scale = 0.5 * n_;
  auto pixel = [&](double x) { return int(std::floor(std::clamp((x + 1.0) * scale, 0.0, double(n_ - 1)))); };
  return PixelRect{pixel(fp.u0), pixel(fp.u1), pixel(fp.w0), pixel(fp.w1), near};
}

void CubeDepthBuffer::demand(const Aabb& box) {
  const glm::dvec3 lo = glm::dvec3(box.min) - eye_, hi = glm::dvec3(box.max) - eye_;
  if (!demanding_) {
    demanding_ = true;
    fill_maxima(-kFar);  // no pixel wanted yet
  }
  if (max_norm_distance(lo, hi) <= 0.0) return;  // never hidden: reads nothing
  for (int face = 0; face < 6; ++face)
    if (const auto r = occludee_pixels(face, lo, hi)) {
      // No occluder is rendered yet, so a tile with a wanted pixel has +inf as its largest depth.
      for (int tj = r->j0 / kTile; tj <= r->j1 / kTile; ++tj)
        for (int ti = r->i0 / kTile; ti <= r->i1 / kTile; ++ti) {
          make_live(face, ti, tj);
          set_tile_max(face, ti, tj, kFar);
        }
      for (int j = r->j0; j <= r->j1; ++j)
        std::fill_n(demand_.begin() + ptrdiff_t((size_t(face) * n_ + j) * n_ + r->i0), r->i1 - r->i0 + 1, 1);
    }
}

// An occluder inside the box writes a pixel only where the rays through its corners meet the
// occluder, at points of the box in the face's pyramid: inside the rectangle occludee_pixels
// gives, at depths >= its `near`. A pixel no deeper than that keeps its depth (add_to_face
// skips it). Tiles whose wanted pixels all are that near are passed over whole; a tile inside
// the rectangle with a wanted pixel deeper answers at once (its largest depth is one such
// pixel); the others are read pixel by pixel.
bool CubeDepthBuffer::may_lower(const Aabb& box) const {
  const glm::dvec3 lo = glm::dvec3(box.min) - eye_, hi = glm::dvec3(box.max) - eye_;
  if (max_norm_distance(lo, hi) <= 0.0) return true;
  for (int face = 0; face < 6; ++face) {
    const auto r = occludee_pixels(face, lo, hi);
    if (!r) continue;
    const float* pixels = depth_.data() + size_t(face) * n_ * n_;
    const bool lowers = tiles_deeper_than(face, r->i0, r->i1, r->j0, r->j1, r->near, [&](int ti, int tj) {
      const int i0 = std::max(r->i0, ti * kTile), i1 = std::min(r->i1 + 1, tile_end(ti));
      const int j0 = std::max(r->j0, tj * kTile), j1 = std::min(r->j1 + 1, tile_end(tj));
      const bool whole = i0 == ti * kTile && i1 == tile_end(ti) && j0 == tj * kTile && j1 == tile_end(tj);
      if (whole || !live(face, ti, tj)) return true;  // not live: all wanted, all +inf
      for (int j = j0; j < j1; ++j)
        for (int i = i0; i < i1; ++i)
          if (double(pixels[size_t(j) * n_ + i]) > r->near && wanted(face, i, j)) return true;
      return false;
    });
    if (lowers) return true;
  }
  return false;
}

bool CubeDepthBuffer::hidden(const Aabb& box) const {
  const glm::dvec3 lo = glm::dvec3(box.min) - eye_, hi = glm::dvec3(box.max) - eye_;
  if (max_norm_distance(lo, hi) <= 0.0) return false;
  for (int face = 0; face < 6; ++face) {
    const auto r = occludee_pixels(face, lo, hi);
    if (!r) continue;
    const float* pixels = depth_.data() + size_t(face) * n_ * n_;
    for (int tj = r->j0 / kTile; tj <= r->j1 / kTile; ++tj)
      for (int ti = r->i0 / kTile; ti <= r->i1 / kTile; ++ti) {
        if (!live(face, ti, tj)) return false;  // its pixels are +inf
        for (int j = std::max(r->j0, tj * kTile); j < std::min(r->j1 + 1, tile_end(tj)); ++j)
          for (int i = std::max(r->i0, ti * kTile); i < std::min(r->i1 + 1, tile_end(ti)); ++i)
            if (!(double(pixels[size_t(j) * n_ + i]) < r->near)) return false;
      }
  }
  return true;
}

float CubeDepthBuffer::depth(int face, int i, int j) const {
  return live(face, i / kTile, j / kTile) ? depth_[(size_t(face) * n_ + j) * n_ + i] : kFar;
}

double CubeDepthBuffer::covered_fraction() const {
  size_t covered = 0;
  for (int face = 0; face < 6; ++face)
    for (int j = 0; j < n_; ++j)
      for (int i = 0; i < n_; ++i) covered += depth(face, i, j) != kFar;
  return double(covered) / double(depth_.size());
}

}  // namespace cellwalk::visibility
