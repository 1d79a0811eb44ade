// HDoV thesis §4.2.2 (Figs. 4.7–4.8), digest §3.3: REVIEW's object buffer, the history of
// queried cells, the history filter and the eviction that cuts the history back.
#include "systems/review/review_object_buffer.hpp"

#include <algorithm>

#include "cellwalk/core/error.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk::review {

Reservation& Reservation::operator=(Reservation&& o) noexcept {
  if (this != &o) {
    reset();
    budget_ = o.budget_;
    bytes_ = o.bytes_;
    o.bytes_ = 0;
  }
  return *this;
}

bool Reservation::try_grow(uint64_t bytes) {
  if (!budget_->try_reserve(bytes)) return false;
  bytes_ += bytes;
  return true;
}

void Reservation::shrink_to(uint64_t bytes) {
  if (budget_ && bytes < bytes_) budget_->release(bytes_ - bytes);
  bytes_ = std::min(bytes, bytes_);
}

void Reservation::reset() {
  if (budget_ && bytes_) budget_->release(bytes_);
  bytes_ = 0;
}

namespace {

// An upper bound of a decoded level's bytes (levels are compacted: at most 3 vertices per
// triangle, each a position, a normal and a colour) — the bound GeometryStore uses.
uint64_t decoded_bound(uint64_t triangles) {
  return sizeof(Mesh) + triangles * (3 * (sizeof(Vec3) * 2 + sizeof(Rgba8)) + 3 * sizeof(uint32_t));
}

uint64_t pages_spanned(const World& world, const LodRecord& level) {
  if (level.bytes == 0) return 0;
  const uint64_t page = world.file().page_size();
  return (level.offset + level.bytes - 1) / page - level.offset / page + 1;
}

// A list trimmed after removals holds at most twice its size, the bound the charges assume.
template <class T>
void trim(std::vector<T>& v) {
  if (v.capacity() > 2 * v.size()) v.shrink_to_fit();
}

}  // namespace

uint64_t fetch_bound(const World& world, ObjectId id) {
  const LodRecord& level = world.lod(id, 0);
  return level.bytes + decoded_bound(level.triangles) + kObjectBookkeepingBytes;
}

std::optional<BufferedObject> fetch_object(const World& world, ObjectId id, MemoryBudget& budget,
                                           FetchCounters& counters) {
  const uint64_t bound = fetch_bound(world, id);
  if (!budget.try_reserve(bound)) return std::nullopt;
  BufferedObject o;
  o.id = id;
  o.box = world.object(id).bounds;
  o.reservation = Reservation(budget, bound);
  Stopwatch watch;
  uint64_t encoded = 0;
  {  // the encoded bytes are freed before the reservation shrinks
    const std::vector<uint8_t> bytes = world.read_level(id, 0);
    encoded = bytes.size();
    counters.io_ms += watch.lap_ms();
    o.mesh = std::make_shared<const Mesh>(world.decode_level(id, 0, bytes));
    counters.decode_ms += watch.lap_ms();
  }
  const uint64_t mesh_bytes = sizeof(Mesh) + o.mesh->byte_size();
  if (mesh_bytes + kObjectBookkeepingBytes > bound - encoded)
    fail(world.file().path() + ": object " + std::to_string(id), "decodes to unreferenced vertices (the file is damaged)");
  o.reservation.shrink_to(mesh_bytes + kObjectBookkeepingBytes);
  ++counters.fetched;
  counters.pages += pages_spanned(world, world.lod(id, 0));
  counters.bytes += encoded;
  return o;
}

const Mesh* ObjectBuffer::mesh(ObjectId id) const {
  auto it = objects_.find(id);
  return it == objects_.end() ? nullptr : it->second.mesh.get();
}

void ObjectBuffer::begin_group(const Aabb& cell) {
  std::erase_if(groups_, [](const Group& g) { return g.members.empty(); });
  trim(groups_);
  groups_.push_back({cell, Aabb{}, {}});
}

bool ObjectBuffer::insert(BufferedObject object) {
  if (objects_.contains(object.id)) return false;
  Group& g = groups_.back();
  g.bounds.extend(object.box);
  g.members.push_back(object.id);
  const ObjectId id = object.id;
  objects_.emplace(id, std::move(object));
  return true;
}

bool ObjectBuffer::record_cell(const Aabb& cell) {
  if (!history_bytes_.try_grow(kHistoryCellBytes)) return false;
  Aabb extent;
  for (const auto& [id, o] : objects_)
    if (o.box.overlaps(cell)) extent.extend(o.box);
  history_.push_back(cell);
  extents_.push_back(extent);
  return true;
}

std::vector<ObjectId> ObjectBuffer::buffered_ids() const {
  std::vector<ObjectId> ids;
  ids.reserve(objects_.size());
  for (const auto& entry : objects_) ids.push_back(entry.first);  // the map is ordered
  return ids;
}

std::vector<Aabb> ObjectBuffer::filtered_history(const Aabb& cell) const {
  std::vector<Aabb> kept;
  for (size_t i = 0; i < history_.size(); ++i)
    if (!extents_[i].empty() && extents_[i].overlaps(cell)) kept.push_back(history_[i]);
  return kept;
}

size_t ObjectBuffer::evict_outside(std::span<const Aabb> keep) {
  ++epoch_;
  auto kept = [&](const Aabb& box) {
    return std::any_of(keep.begin(), keep.end(), [&](const Aabb& k) { return box.overlaps(k); });
  };
  size_t removed = 0;
  for (Group& g : groups_) {
    std::erase_if(g.members, [&](ObjectId id) {
      if (kept(objects_.at(id).box)) return false;
      objects_.erase(id);
      ++removed;
      return true;
    });
    trim(g.members);
  }
  if (!groups_.empty()) {  // emptied groups go, but not the newest: a query may be filling it
    Group newest = std::move(groups_.back());
    groups_.pop_back();
    std::erase_if(groups_, [](const Group& g) { return g.members.empty(); });
    groups_.push_back(std::move(newest));
    trim(groups_);
  }
  auto same = [](const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; };
  for (size_t i = history_.size(); i-- > 0;)
    if (std::none_of(keep.begin(), keep.end(), [&](const Aabb& k) { return same(k, history_[i]); })) {
      history_.erase(history_.begin() + std::ptrdiff_t(i));
      extents_.erase(extents_.begin() + std::ptrdiff_t(i));
    }
  trim_history();
  return removed;
}

void ObjectBuffer::clear() {
  ++epoch_;
  groups_.clear();
  objects_.clear();
  history_.clear();
  extents_.clear();
  trim(groups_);
  trim_history();
}

void ObjectBuffer::trim_history() {
  trim(history_);
  trim(extents_);
  history_bytes_.shrink_to(history_.size() * kHistoryCellBytes);
}

}  // namespace cellwalk::review
