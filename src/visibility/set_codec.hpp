// Visible sets on disk, after vLOD §2.3–§2.4 (digest 001 §3.3–§3.4): sorted integer ids as
// gaps in LEB128 varints (vLOD's RLE + delimiter code, replaced by bytes: simpler, and sets of
// city cells are long lists of small gaps), Δs between neighbouring cells as the pair
// (added, removed) of gap-coded lists, and plain bitmasks for dense sets (ours: the stored
// form is the smallest of the three, so never larger than a bitmask and its tag). Layout in docs/format.md, "Visibility sections".
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cellwalk/scene/scene.hpp"

namespace cellwalk::visibility {

void put_varint(std::vector<uint8_t>& out, uint64_t value);
// Reads at `pos` and advances it. Throws Error naming `where` and the offset on truncation or
// a varint longer than 10 bytes.
uint64_t get_varint(std::span<const uint8_t> bytes, size_t& pos, const std::string& where);

// Appends: varint count, then varint first id, then varint (id - previous - 1) for the rest.
// REQUIRES: ids strictly ascending.
void append_set(std::vector<uint8_t>& out, std::span<const ObjectId> ids);
// Reads a set written by append_set at `pos`. Throws Error naming `where` when the bytes are
// damaged or an id is >= id_limit (the world's object count). Allocates at most one id per
// remaining byte, so damaged counts cannot exhaust memory.
std::vector<ObjectId> read_set(std::span<const uint8_t> bytes, size_t& pos, const std::string& where,
                               uint64_t id_limit);

// From one cell's set to a neighbour's: to = (from ∪ added) \ removed.
struct SetDelta {
  std::vector<ObjectId> added;
  std::vector<ObjectId> removed;
};
SetDelta set_delta(std::span<const ObjectId> from, std::span<const ObjectId> to);
// REQUIRES: delta was made from `from` (added ∩ from = ∅, removed ⊆ from); otherwise the result
// is still a sorted set but not the original.
std::vector<ObjectId> apply_delta(std::span<const ObjectId> from, const SetDelta& delta);
void append_delta(std::vector<uint8_t>& out, const SetDelta& delta);
SetDelta read_delta(std::span<const uint8_t> bytes, size_t& pos, const std::string& where, uint64_t id_limit);

// The size of the same set as a plain bitmask over all objects: ceil(object_count / 8).
inline uint64_t bitmask_bytes(uint64_t object_count) { return (object_count + 7) / 8; }

// Appends the set as a plain bitmask of bitmask_bytes(object_count) bytes: id i is bit i % 8
// (least significant first) of byte i / 8. The form of choice for dense sets: it bounds a
// stored set's size. REQUIRES: ids strictly ascending, all < object_count.
void append_bitmask(std::vector<uint8_t>& out, std::span<const ObjectId> ids, uint64_t object_count);
// Reads a bitmask written by append_bitmask at `pos`. Throws Error naming `where` when the
// bytes are too few or a bit past object_count is set.
std::vector<ObjectId> read_bitmask(std::span<const uint8_t> bytes, size_t& pos, const std::string& where,
                                   uint64_t object_count);

}  // namespace cellwalk::visibility
