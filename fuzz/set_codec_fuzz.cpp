// libFuzzer target for the visible-set codec (src/visibility/set_codec.hpp): any input must
// decode (as a Δ, and as a bitmask) to strictly ascending in-range ids that re-encode to the
// same bytes, or give a cellwalk::Error; never a crash or an unbounded allocation.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "cellwalk/core/error.hpp"
#include "visibility/set_codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cellwalk::visibility;
  const std::span<const uint8_t> bytes(data, size);
  size_t pos = 0;
  try {
    const SetDelta d = read_delta(bytes, pos, "fuzz", 1u << 20);
    for (const auto* list : {&d.added, &d.removed})
      for (size_t i = 1; i < list->size(); ++i)
        if ((*list)[i] <= (*list)[i - 1]) std::abort();
    std::vector<uint8_t> again;
    append_delta(again, d);
    std::vector<cellwalk::ObjectId> base = apply_delta(d.removed, d);  // removed ⊆ base holds for this base
    size_t p2 = 0;
    const SetDelta d2 = read_delta(again, p2, "fuzz-again", 1u << 20);
    if (d2.added != d.added || d2.removed != d.removed || p2 != again.size()) std::abort();
    for (size_t i = 1; i < base.size(); ++i)
      if (base[i] <= base[i - 1]) std::abort();
  } catch (const cellwalk::Error&) {
  }
  // The bitmask form: the first byte gives the object count, the rest is the mask.
  if (size > 0) {
    const uint64_t objects = data[0];
    size_t at = 1;
    try {
      const std::vector<cellwalk::ObjectId> ids = read_bitmask(bytes, at, "fuzz", objects);
      std::vector<uint8_t> again{data[0]};
      append_bitmask(again, ids, objects);
      if (at != again.size() || !std::equal(again.begin(), again.end(), data)) std::abort();
    } catch (const cellwalk::Error&) {
    }
  }
  return 0;
}
