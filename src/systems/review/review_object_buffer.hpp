// REVIEW's object buffer and its history of queried cells (HDoV thesis §4.2.2, Figs. 4.7–4.8;
// digest §3.3, §4 "REVIEW object buffer"): decoded objects grouped by the cell that retrieved
// them, under a hard byte budget; the cells whose queries completed, each with the extent of the
// objects overlapping it (for the history filter); and the eviction that keeps only objects
// overlapping the live cells and cuts the history back to them (the digest's fix).
//
// Invariant (what CSearch relies on): every object whose box overlaps a cell in history() is in
// the buffer.
//
// Everything the buffer holds is charged to its budget before it is allocated (docs/review.md,
// "Memory"): each object's mesh plus kObjectBookkeepingBytes (which includes its slot in a
// prefetch's list of buffered ids), each history cell kHistoryCellBytes. Lists are trimmed after
// evictions so none holds more than twice what it is charged for.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "cellwalk/store/memory_budget.hpp"
#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/index/rtree.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk::review {

// Bytes held in a MemoryBudget, released when the reservation is destroyed. Move-only.
class Reservation {
 public:
  Reservation() = default;
  Reservation(MemoryBudget& budget, uint64_t bytes) : budget_(&budget), bytes_(bytes) {}
  Reservation(Reservation&& o) noexcept : budget_(o.budget_), bytes_(o.bytes_) { o.bytes_ = 0; }
  Reservation& operator=(Reservation&& o) noexcept;
  Reservation(const Reservation&) = delete;
  Reservation& operator=(const Reservation&) = delete;
  ~Reservation() { reset(); }
  // Adds `bytes` if the budget takes them; returns whether it did.
  bool try_grow(uint64_t bytes);
  // Gives back all but `bytes`. REQUIRES: bytes <= this->bytes().
  void shrink_to(uint64_t bytes);
  void reset();
  uint64_t bytes() const { return bytes_; }

 private:
  MemoryBudget* budget_ = nullptr;
  uint64_t bytes_ = 0;
};

struct BufferedObject {
  ObjectId id = 0;
  Aabb box;
  std::shared_ptr<const Mesh> mesh;  // level 0
  Reservation reservation;           // its bytes in the buffer's budget
};

// The objects one query retrieved (§4.2.2: the buffer is organised by retrieving cell).
struct CellGroup {
  Aabb cell;
  Aabb bounds;  // of its objects; an upper bound after evictions
  std::vector<ObjectId> members;
};

// What one buffered object costs beside its mesh's arrays and sizeof(Mesh), an upper estimate
// from the node types: its node in the buffer's ordered map (the value and a red-black node's
// colour and three links), its slot in its group's member list and a share of a group (a
// non-empty group has at least one member; both lists hold at most twice their size), its slot
// in a prefetch's payload (alive beside the map node while a prefetch is merged), the mesh's
// shared_ptr control block, the allocator's header on the map node and on the mesh's block and
// four arrays, and its slot in a prefetch's list of buffered ids (buffered_ids()).
inline constexpr uint64_t kObjectBookkeepingBytes =
    sizeof(std::pair<const ObjectId, BufferedObject>) + 4 * sizeof(void*) + kHeapBlockBytes +
    2 * sizeof(ObjectId) + 2 * sizeof(CellGroup) + 2 * sizeof(BufferedObject) + 2 * sizeof(long) + sizeof(void*) +
    5 * kHeapBlockBytes + sizeof(ObjectId);
// One history cell: the cell and its extent (two lists, each at most twice its size) and the
// same in the two filtered copies a demand query and a prefetch may hold.
inline constexpr uint64_t kHistoryCellBytes = 8 * sizeof(Aabb);

struct FetchCounters {
  uint64_t fetched = 0, pages = 0, bytes = 0;
  double io_ms = 0, decode_ms = 0;
};

// Reads and decodes level 0 of `id` with its bytes reserved in `budget` throughout (the encoded
// bytes, a decoded bound and kObjectBookkeepingBytes first; the decoded mesh and the bookkeeping
// once the encoded bytes are freed). nullopt when the budget refuses; nothing is read then. Thread-safe for distinct calls (World reads are).
std::optional<BufferedObject> fetch_object(const World& world, ObjectId id, MemoryBudget& budget,
                                           FetchCounters& counters);
// The bytes fetch_object reserves before reading: what one object needs free to load.
uint64_t fetch_bound(const World& world, ObjectId id);

class ObjectBuffer {
 public:
  // limit 0 = unbounded.
  explicit ObjectBuffer(uint64_t limit_bytes) : budget_(limit_bytes), history_bytes_(budget_, 0) {}

  MemoryBudget& budget() { return budget_; }
  const MemoryBudget& budget() const { return budget_; }
  bool contains(ObjectId id) const { return objects_.contains(id); }
  const Mesh* mesh(ObjectId id) const;
  size_t size() const { return objects_.size(); }

  // Starts the group of the objects retrieved by `cell`; insert() adds to it.
  void begin_group(const Aabb& cell);
  // Adds an object to the newest group. Returns false (and drops it) if it is already buffered.
  // REQUIRES: begin_group() was called.
  bool insert(BufferedObject object);
  // The query of `cell` completed: every object overlapping it is buffered. Records the cell
  // with the extent of those objects if the budget has kHistoryCellBytes for it; returns whether
  // it did (a cell left out only makes later searches return more, never less).
  bool record_cell(const Aabb& cell);
  // The buffered ids, sorted: what a prefetch running beside the buffer must not fetch again.
  // Its slots are charged with the objects; it must be freed before any of them is evicted.
  std::vector<ObjectId> buffered_ids() const;

  // The history filter (§4.2.2): the history cells whose objects' extent overlaps `cell`; the
  // others cannot change CSearch's result for `cell`.
  std::vector<Aabb> filtered_history(const Aabb& cell) const;
  std::span<const Aabb> history() const { return history_; }

  // Fig. 4.8 with the digest's fix: removes every object overlapping none of `keep`, and keeps
  // in the history only the cells that are among `keep`. Returns the objects removed. The newest
  // group stays (a query may be filling it).
  size_t evict_outside(std::span<const Aabb> keep);
  // Removes everything and forgets the history (BOX replaces its buffer per query).
  void clear();
  // Counts evict_outside() calls: a prefetch started before one cannot enter the history.
  uint64_t eviction_epoch() const { return epoch_; }

  using Group = CellGroup;
  const std::vector<Group>& groups() const { return groups_; }
  const BufferedObject& object(ObjectId id) const { return objects_.at(id); }

 private:
  void trim_history();

  MemoryBudget budget_;  // declared first: objects release into it when destroyed
  // Ordered, not hashed: a hash table's bucket array never shrinks after evictions.
  std::map<ObjectId, BufferedObject> objects_;
  std::vector<Group> groups_;
  std::vector<Aabb> history_, extents_;  // extents_[i]: union of objects overlapping history_[i]
  Reservation history_bytes_;            // kHistoryCellBytes per history cell
  uint64_t epoch_ = 0;
};

}  // namespace cellwalk::review
