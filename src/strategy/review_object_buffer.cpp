// HDoV thesis §4.2.2 (Figs. 4.7–4.8), digest §3.3: REVIEW's object buffer, the history of
// queried cells, the history filter and the eviction that cuts the history back.
#include "strategy/review_object_buffer.hpp"

#include <algorithm>

#include "cellwalk/error.hpp"
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

}  // namespace

uint64_t fetch_bound(const World& world, ObjectId id) {
  const LodRecord& level = world.lod(id, 0);
  return level.bytes + decoded_bound(level.triangles);
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
  const std::vector<uint8_t> bytes = world.read_level(id, 0);
  counters.io_ms += watch.lap_ms();
  o.mesh = std::make_shared<const Mesh>(world.decode_level(id, 0, bytes));
  counters.decode_ms += watch.lap_ms();
  const uint64_t mesh_bytes = sizeof(Mesh) + o.mesh->byte_size();
  if (mesh_bytes > bound - bytes.size())
    fail(world.file().path() + ": object " + std::to_string(id), "decodes to unreferenced vertices (the file is damaged)");
  o.reservation.shrink_to(mesh_bytes);
  ++counters.fetched;
  counters.pages += pages_spanned(world, world.lod(id, 0));
  counters.bytes += bytes.size();
  return o;
}

const Mesh* ObjectBuffer::mesh(ObjectId id) const {
  auto it = objects_.find(id);
  return it == objects_.end() ? nullptr : it->second.mesh.get();
}

size_t ObjectBuffer::begin_group(const Aabb& cell) {
  // Groups emptied by evictions go here, not in evict_outside(): a query's group index must
  // stay valid while it runs.
  std::erase_if(groups_, [](const Group& g) { return g.members.empty(); });
  groups_.push_back({cell, Aabb{}, {}});
  return groups_.size() - 1;
}

bool ObjectBuffer::insert(size_t group, BufferedObject object) {
  if (objects_.count(object.id)) return false;
  Group& g = groups_.at(group);
  g.bounds.extend(object.box);
  g.members.push_back(object.id);
  const ObjectId id = object.id;
  objects_.emplace(id, std::move(object));
  return true;
}

void ObjectBuffer::record_cell(const Aabb& cell) {
  Aabb extent;
  for (const auto& [id, o] : objects_)
    if (o.box.overlaps(cell)) extent.extend(o.box);
  history_.push_back(cell);
  extents_.push_back(extent);
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
  }
  auto same = [](const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; };
  for (size_t i = history_.size(); i-- > 0;)
    if (std::none_of(keep.begin(), keep.end(), [&](const Aabb& k) { return same(k, history_[i]); })) {
      history_.erase(history_.begin() + std::ptrdiff_t(i));
      extents_.erase(extents_.begin() + std::ptrdiff_t(i));
    }
  return removed;
}

void ObjectBuffer::clear() {
  ++epoch_;
  groups_.clear();
  objects_.clear();
  history_.clear();
  extents_.clear();
}

}  // namespace cellwalk::review
