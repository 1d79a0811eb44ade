// Li & Chiang's viewpoint configurations (seed 003, "Visibility Pre-computation"): a position
// (a view cell) and an orientation (one of `sectors` equal ranges of yaw). The visible set of a
// configuration is the cell's stored from-region set less the objects no view direction of the
// sector can see: an object is kept when some direction from a point of the cell to a point of
// its box, in x and z, lies within the sector widened by the camera's horizontal half-field.
// That test is exact for boxes (docs/lichiang.md, "Configurations").
#pragma once

#include <optional>

#include "cellwalk/core/camera.hpp"
#include "cellwalk/core/geometry.hpp"

namespace cellwalk::lichiang {

// A range of yaws (radians, the camera's convention: 0 looks along −Z, positive turns left),
// from `lo` counter-clockwise to `hi`; `all` covers every direction.
struct YawRange {
  double lo = 0.0, hi = 0.0;
  bool all = false;
  bool contains(double yaw) const;
  bool meets(const YawRange& other) const;
};

// The yaw of a direction in the x-z plane.
double yaw_of(double x, double z);

// The yaws of every direction from a point of `from` to a point of `to`, in x and z. All
// directions when their x-z footprints meet.
YawRange directions_between(const Aabb& from, const Aabb& to);

// The most the yaw of a ray through the camera's image departs from the camera's yaw: the
// horizontal half-field when level, wider when pitched; nullopt when the image holds the
// vertical (every yaw is seen).
std::optional<double> yaw_half_extent(const Camera& camera);

// Sector s of `sectors` covers yaws [2π·s/sectors, 2π·(s+1)/sectors).
int sector_of(double yaw, int sectors);
// Sectors s − spread .. s + spread, widened by `margin` on both sides (nullopt margin: all).
YawRange sector_range(int sector, int spread, int sectors, std::optional<double> margin);

}  // namespace cellwalk::lichiang
