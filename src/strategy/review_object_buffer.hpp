// REVIEW's object buffer and its history of queried cells (HDoV thesis §4.2.2, Figs. 4.7–4.8;
// digest §3.3, §4 "REVIEW object buffer"): decoded objects grouped by the cell that retrieved
// them, under a hard byte budget; the cells whose queries completed, each with the extent of the
// objects overlapping it (for the history filter); and the eviction that keeps only objects
// overlapping the live cells and cuts the history back to them (the digest's fix).
//
// Invariant (what CSearch relies on): every object whose box overlaps a cell in history() is in
// the buffer.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include "cellwalk/memory_budget.hpp"
#include "cellwalk/mesh.hpp"
#include "cellwalk/world.hpp"

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

struct FetchCounters {
  uint64_t fetched = 0, pages = 0, bytes = 0;
  double io_ms = 0, decode_ms = 0;
};

// Reads and decodes level 0 of `id` with its bytes reserved in `budget` throughout (the encoded
// bytes and a decoded bound first, the decoded mesh after). nullopt when the budget refuses;
// nothing is read then. Thread-safe for distinct calls (World reads are).
std::optional<BufferedObject> fetch_object(const World& world, ObjectId id, MemoryBudget& budget,
                                           FetchCounters& counters);
// The bytes fetch_object reserves before reading: what one object needs free to load.
uint64_t fetch_bound(const World& world, ObjectId id);

class ObjectBuffer {
 public:
  // limit 0 = unbounded.
  explicit ObjectBuffer(uint64_t limit_bytes) : budget_(limit_bytes) {}

  MemoryBudget& budget() { return budget_; }
  const MemoryBudget& budget() const { return budget_; }
  bool contains(ObjectId id) const { return objects_.count(id) != 0; }
  const Mesh* mesh(ObjectId id) const;
  size_t size() const { return objects_.size(); }

  // A group for the objects retrieved by `cell`; returns its index for insert(), valid until
  // the next begin_group().
  size_t begin_group(const Aabb& cell);
  // Adds an object to a group. Returns false (and drops it) if it is already buffered.
  bool insert(size_t group, BufferedObject object);
  // The query of `cell` completed: every object overlapping it is buffered. Records the cell
  // with the extent of those objects.
  void record_cell(const Aabb& cell);

  // The history filter (§4.2.2): the history cells whose objects' extent overlaps `cell`; the
  // others cannot change CSearch's result for `cell`.
  std::vector<Aabb> filtered_history(const Aabb& cell) const;
  std::span<const Aabb> history() const { return history_; }

  // Fig. 4.8 with the digest's fix: removes every object overlapping none of `keep`, and keeps
  // in the history only the cells that are among `keep`. Returns the objects removed.
  size_t evict_outside(std::span<const Aabb> keep);
  // Removes everything and forgets the history (BOX replaces its buffer per query).
  void clear();
  // Counts evict_outside() calls: a prefetch started before one cannot enter the history.
  uint64_t eviction_epoch() const { return epoch_; }

  struct Group {
    Aabb cell;
    Aabb bounds;  // of its objects; an upper bound after evictions
    std::vector<ObjectId> members;
  };
  const std::vector<Group>& groups() const { return groups_; }
  const BufferedObject& object(ObjectId id) const { return objects_.at(id); }

 private:
  MemoryBudget budget_;  // declared first: objects release into it when destroyed
  std::unordered_map<ObjectId, BufferedObject> objects_;
  std::vector<Group> groups_;
  std::vector<Aabb> history_, extents_;  // extents_[i]: union of objects overlapping history_[i]
  uint64_t epoch_ = 0;
};

}  // namespace cellwalk::review
