// Gap-varint coding of sorted id sets and of Δs between neighbouring cells: vLOD §2.3–§2.4
// (digest 001 §3.3–§3.4), with LEB128 varints in place of the delimiter code.
#include "visibility/set_codec.hpp"

#include <algorithm>
#include <iterator>

#include "cellwalk/core/error.hpp"

namespace cellwalk::visibility {

void put_varint(std::vector<uint8_t>& out, uint64_t value) {
  while (value >= 0x80) {
    out.push_back(uint8_t(value | 0x80));
    value >>= 7;
  }
  out.push_back(uint8_t(value));
}

uint64_t get_varint(std::span<const uint8_t> bytes, size_t& pos, const std::string& where) {
  uint64_t value = 0;
  for (int shift = 0; shift < 70; shift += 7) {
    if (pos >= bytes.size()) fail(where + "@" + std::to_string(pos), "truncated varint");
    const uint8_t b = bytes[pos++];
    if (shift == 63 && b > 1) fail(where + "@" + std::to_string(pos - 1), "varint overflows 64 bits");
    value |= uint64_t(b & 0x7F) << shift;
    if (!(b & 0x80)) return value;
  }
  fail(where + "@" + std::to_string(pos), "varint longer than 10 bytes");
}

void append_set(std::vector<uint8_t>& out, std::span<const ObjectId> ids) {
  put_varint(out, ids.size());
  for (size_t i = 0; i < ids.size(); ++i) put_varint(out, i == 0 ? ids[0] : ids[i] - ids[i - 1] - 1);
}

std::vector<ObjectId> read_set(std::span<const uint8_t> bytes, size_t& pos, const std::string& where,
                               uint64_t id_limit) {
  const uint64_t count = get_varint(bytes, pos, where);
  if (count > bytes.size() - pos) fail(where + "@" + std::to_string(pos), "set of " + std::to_string(count) + " ids is longer than its bytes");
  std::vector<ObjectId> ids;
  ids.reserve(count);
  uint64_t next = 0;  // the smallest id the next entry may have
  for (uint64_t i = 0; i < count; ++i) {
    const uint64_t gap = get_varint(bytes, pos, where);
    const uint64_t id = next + gap;
    if (gap >= id_limit || id >= id_limit)
      fail(where + "@" + std::to_string(pos), "object id " + std::to_string(id) + " out of range (" + std::to_string(id_limit) + " objects)");
    ids.push_back(ObjectId(id));
    next = id + 1;
  }
  return ids;
}

SetDelta set_delta(std::span<const ObjectId> from, std::span<const ObjectId> to) {
  SetDelta d;
  std::set_difference(to.begin(), to.end(), from.begin(), from.end(), std::back_inserter(d.added));
  std::set_difference(from.begin(), from.end(), to.begin(), to.end(), std::back_inserter(d.removed));
  return d;
}

std::vector<ObjectId> apply_delta(std::span<const ObjectId> from, const SetDelta& delta) {
  std::vector<ObjectId> kept, out;
  std::set_difference(from.begin(), from.end(), delta.removed.begin(), delta.removed.end(), std::back_inserter(kept));
  std::set_union(kept.begin(), kept.end(), delta.added.begin(), delta.added.end(), std::back_inserter(out));
  return out;
}

void append_delta(std::vector<uint8_t>& out, const SetDelta& delta) {
  append_set(out, delta.added);
  append_set(out, delta.removed);
}

SetDelta read_delta(std::span<const uint8_t> bytes, size_t& pos, const std::string& where, uint64_t id_limit) {
  SetDelta d;
  d.added = read_set(bytes, pos, where, id_limit);
  d.removed = read_set(bytes, pos, where, id_limit);
  return d;
}

void append_bitmask(std::vector<uint8_t>& out, std::span<const ObjectId> ids, uint64_t object_count) {
  const size_t base = out.size();
  out.resize(base + bitmask_bytes(object_count), 0);
  for (ObjectId id : ids) out[base + id / 8] |= uint8_t(1u << (id % 8));
}

std::vector<ObjectId> read_bitmask(std::span<const uint8_t> bytes, size_t& pos, const std::string& where,
                                   uint64_t object_count) {
  const uint64_t length = bitmask_bytes(object_count);
  if (pos > bytes.size() || length > bytes.size() - pos)
    fail(where + "@" + std::to_string(pos), "bitmask of " + std::to_string(length) + " bytes is truncated");
  std::vector<ObjectId> ids;
  for (uint64_t byte = 0; byte < length; ++byte)
    for (uint32_t bit = 0, b = bytes[pos + byte]; b != 0; ++bit, b >>= 1) {
      if (!(b & 1)) continue;
      const uint64_t id = byte * 8 + bit;
      if (id >= object_count)
        fail(where + "@" + std::to_string(pos + byte), "bitmask sets object " + std::to_string(id) + " past the last (" + std::to_string(object_count) + " objects)");
      ids.push_back(ObjectId(id));
    }
  pos += length;
  return ids;
}

}  // namespace cellwalk::visibility
