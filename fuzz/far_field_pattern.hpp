// A cell's far field made without GL, for the fuzz targets of the stratified files: faces of R²
// texels showing the objects' ids in turn at depths beyond the box (every third texel), the other
// texels empty; cells alternate between four faces and two.
#pragma once

#include <cstdint>
#include <vector>

#include "cellwalk/systems/stratified/far_field.hpp"

namespace cellwalk::fuzz {

inline stratified::CellFarField far_field_pattern(uint32_t cell, uint64_t objects, float b, int resolution) {
  stratified::CellFarField field;
  const size_t texels = size_t(resolution) * size_t(resolution);
  for (int face = 0; face < 4; face += 1 + int(cell % 2)) {
    stratified::FaceImage f;
    f.face = face;
    f.color = {resolution, resolution, std::vector<uint8_t>(texels * 4, 0)};
    f.ids = {resolution, resolution, std::vector<uint32_t>(texels, 0)};
    f.depth.assign(texels, 0.0f);
    for (size_t t = 0; t < texels; t += 3) {
      f.ids.ids[t] = uint32_t(1 + (t + cell) % objects);
      f.color.rgba[t * 4 + 3] = 255;
      f.depth[t] = b * (0.5f + 0.1f * float(t % 7));
    }
    field.faces.push_back(std::move(f));
  }
  return field;
}

}  // namespace cellwalk::fuzz
