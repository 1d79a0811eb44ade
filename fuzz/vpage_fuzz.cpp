// libFuzzer target for the HDoV-tree's pages (src/systems/visual/hdov_tree_file.cpp, docs/format.md
// "HDoV-tree file"): any bytes must decode as a node page and as a V-page, or give a
// cellwalk::Error; what decodes must respect the page's bounds. Never a crash or a hang.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/visual/hdov_tree.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cellwalk;
  const std::span<const uint8_t> bytes(data, size);
  try {
    const HdovNode node = decode_hdov_node(bytes, "fuzz");
    if (24 + node.entries.size() * 28 + node.lods.size() * 16 > size) std::abort();
  } catch (const Error&) {
  }
  try {
    const uint32_t entries = size > 0 ? data[0] % 32 : 0;
    for (const VEntry& v : decode_vpage(bytes, entries, "fuzz"))
      if (!std::isfinite(v.dov) || v.dov < 0) std::abort();
  } catch (const Error&) {
  }
  return 0;
}
