// The level of detail each object is drawn at from a view cell: the coarsest level whose error,
// projected from anywhere in the cell, stays under the pixel bound.
// Seed: 001 vLOD §2.2 (digest §3.2: the corrected per-cell bound; the paper's text behind
// CellBoundFormula::kFaithful). The same rule serves the precompute (vLOD(C) is computed on the
// levels it selects) and the run time (which draws them), so both read it from here.
#pragma once

#include <cstdint>
#include <string>

#include "cellwalk/lod/screen_error.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk::visibility {

struct CellLodRule {
  Lens lens;                 // the largest image the levels are chosen for
  float pixel_error = 1.0f;  // δ_s: the worst screen error allowed, pixels (< 1 in the seed)
  CellBoundFormula formula = CellBoundFormula::kCorrected;
};

// "px=1,h=480,fov=60,aspect=1.33333,formula=corrected": stored with the sets, so the run time
// draws what the precompute chose. parse throws Error naming `where` on anything else.
std::string to_string(const CellLodRule& rule);
CellLodRule parse_cell_lod_rule(const std::string& text, const std::string& where);

// The coarsest level of `id` whose object-space error times cell_pixels_per_unit(cell, object)
// is below rule.pixel_error; level 0 when the object's box meets the cell (L_min = 0).
uint32_t cell_level(const World& world, ObjectId id, const Aabb& cell, const CellLodRule& rule);

// Whether levels chosen by `rule` keep their bound in images made with `lens` at its viewport
// height: the largest magnification f_px / cos² φ_max of `lens` is at most the rule's.
bool rule_covers(const CellLodRule& rule, const Lens& lens);

}  // namespace cellwalk::visibility
