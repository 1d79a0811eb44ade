// vLOD §2.2 (digest 001 §3.2): the per-cell level of detail.
#include "cellwalk/visibility/cell_lod.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "cellwalk/core/error.hpp"

namespace cellwalk::visibility {

namespace {

constexpr float kDegrees = 57.29577951308232f;

float magnification(const Lens& lens) {
  const float c = std::cos(max_off_axis_angle(lens));
  return focal_length_px(lens) / (c * c);
}

float number_of(const std::string& value, const std::string& key, const std::string& where) {
  char* end = nullptr;
  const float v = std::strtof(value.c_str(), &end);
  if (value.empty() || *end != '\0' || !std::isfinite(v) || v <= 0.0f)
    fail(where, "level rule '" + key + "=" + value + "' needs a positive number");
  return v;
}

}  // namespace

std::string to_string(const CellLodRule& rule) {
  char text[160];
  std::snprintf(text, sizeof text, "px=%g,h=%g,fov=%g,aspect=%g,formula=%s", double(rule.pixel_error),
                double(rule.lens.viewport_height_px), double(rule.lens.fov_y_rad * kDegrees), double(rule.lens.aspect),
                rule.formula == CellBoundFormula::kCorrected ? "corrected" : "faithful");
  return text;
}

CellLodRule parse_cell_lod_rule(const std::string& text, const std::string& where) {
  CellLodRule rule;
  std::istringstream in(text);
  int seen = 0;
  for (std::string field; std::getline(in, field, ',');) {
    const size_t eq = field.find('=');
    const std::string key = field.substr(0, eq), value = eq == std::string::npos ? "" : field.substr(eq + 1);
    if (key == "formula") {
      if (value != "corrected" && value != "faithful") fail(where, "level rule formula '" + value + "': expected corrected or faithful");
      rule.formula = value == "corrected" ? CellBoundFormula::kCorrected : CellBoundFormula::kFaithful;
    } else if (key == "px") {
      rule.pixel_error = number_of(value, key, where);
    } else if (key == "h") {
      rule.lens.viewport_height_px = number_of(value, key, where);
    } else if (key == "fov") {
      rule.lens.fov_y_rad = number_of(value, key, where) / kDegrees;
    } else if (key == "aspect") {
      rule.lens.aspect = number_of(value, key, where);
    } else {
      fail(where, "level rule '" + text + "': unknown field '" + key + "' (px, h, fov, aspect, formula)");
    }
    ++seen;
  }
  if (seen != 5) fail(where, "level rule '" + text + "' needs px, h, fov, aspect and formula");
  return rule;
}

uint32_t cell_level(const World& world, ObjectId id, const Aabb& cell, const CellLodRule& rule) {
  const ObjectRecord& object = world.object(id);
  if (distance_between_boxes(cell, object.bounds) <= 0.0f) return 0;  // the viewer may touch it
  const float pixels = cell_pixels_per_unit(cell, object.bounds, rule.lens, rule.formula);
  if (!std::isfinite(pixels)) return 0;
  uint32_t level = 0;
  for (uint32_t l = 1; l < object.lod_count; ++l)
    if (world.lod(id, l).error * pixels < rule.pixel_error) level = l;
  return level;
}

bool rule_covers(const CellLodRule& rule, const Lens& lens) {
  return magnification(lens) <= magnification(rule.lens) * (1.0f + 1e-5f);
}

}  // namespace cellwalk::visibility
