// libFuzzer target for the k-d HDoV scene tree file's tables (src/systems/scene_tree/scene_tree.cpp,
// docs/scene-tree.md "Tree file"; the sections sit inside checksummed pages that
// world_file_fuzz.cpp covers). Input: u16 object count K, K bytes of per-object level counts,
// u32 geometry section size, u32 length of the kd-nodes bytes, those bytes, then the kd-levels
// bytes. Any input must decode to consistent tables or give a cellwalk::Error; never a crash.
// Seeds: tests/data/seeds/scene_tree_*.bin.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "systems/scene_tree/scene_tree_format.hpp"

namespace {

// Reads a little-endian value at `at` if it fits, advancing `at`; 0 past the end.
template <typename T>
T take(const uint8_t* data, size_t size, size_t& at) {
  T v = 0;
  if (size - at >= sizeof(T)) std::memcpy(&v, data + at, sizeof(T)), at += sizeof(T);
  else at = size;
  return v;
}

// What read_tables promises of tables it accepts.
void check(const cellwalk::scene_tree_format::Tables& t, size_t objects, uint64_t geometry) {
  using namespace cellwalk;
  if (t.nodes.size() != 2 * objects - 1) std::abort();
  std::vector<uint8_t> seen(objects, 0);
  for (size_t i = 0; i < t.nodes.size(); ++i) {
    const SceneTreeNode& n = t.nodes[i];
    if (n.is_leaf()) {
      if (n.object >= objects || seen[n.object]++) std::abort();
      continue;
    }
    for (NodeIndex c : n.child)
      if (c <= i || c >= t.nodes.size() || t.nodes[c].parent != i) std::abort();
    if (uint64_t(n.first_level) + n.level_count > t.levels.size()) std::abort();
  }
  for (const AggregateLevel& l : t.levels)
    if (l.offset > geometry || l.bytes > geometry - l.offset) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  size_t at = 0;
  const size_t objects = take<uint16_t>(data, size, at) % 1024;
  std::vector<uint32_t> lod_counts;
  for (size_t o = 0; o < objects && at < size; ++o) lod_counts.push_back(data[at++] % 8);
  const uint64_t geometry = take<uint32_t>(data, size, at);
  const size_t nodes_length = std::min<size_t>(take<uint32_t>(data, size, at), size - at);
  const std::vector<uint8_t> nodes(data + at, data + at + nodes_length);
  const std::vector<uint8_t> levels(data + at + nodes_length, data + size);
  try {
    check(cellwalk::scene_tree_format::read_tables(nodes, levels, geometry, lod_counts, "fuzz"), lod_counts.size(), geometry);
  } catch (const cellwalk::Error&) {
  }
  return 0;
}
