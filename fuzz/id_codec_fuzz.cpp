// libFuzzer target for the id-set codecs (include/cellwalk/visibility/id_codec.hpp): the first
// byte picks the codec; the rest must decode to strictly ascending ids below the limit that
// re-encode and decode to the same ids, or give a cellwalk::Error; never a crash or an
// unbounded allocation (a run's length is bounded by the limit, 2^20 ids here).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <iterator>

#include "cellwalk/core/error.hpp"
#include "cellwalk/visibility/id_codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cellwalk::visibility;
  if (size == 0) return 0;
  constexpr uint64_t kLimit = 1u << 20;
  const IdCodec codec = kIdCodecs[data[0] % std::size(kIdCodecs)];
  const std::span<const uint8_t> bytes(data + 1, size - 1);
  size_t pos = 0;
  try {
    while (pos < bytes.size()) {  // records concatenate: read them all
      const size_t start = pos;
      const std::vector<uint32_t> ids = decode_ids(codec, bytes, pos, "fuzz", kLimit);
      if (pos <= start || pos > bytes.size()) std::abort();
      for (size_t i = 0; i < ids.size(); ++i)
        if (ids[i] >= kLimit || (i > 0 && ids[i] <= ids[i - 1])) std::abort();
      std::vector<uint8_t> again;
      encode_ids(codec, ids, again);
      size_t p2 = 0;
      if (decode_ids(codec, again, p2, "fuzz-again", kLimit) != ids || p2 != again.size())
        std::abort();
    }
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
