// Where GeometryStore reads a level's encoded bytes from: the seam between the store's cache and
// its storage. The world file's verified pages are the default; an object database built from the
// world (object_database.hpp, Li & Chiang's objects in a DBMS, fetched per object) is the other.
// Either way the bytes are the world file's own encoding, decoded by World::decode_level.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cellwalk/scene/mesh.hpp"

namespace cellwalk {

class World;

// Thread-safety: read_level may be called from several threads at once (a prefetching loader
// beside the frame's own reads).
class LevelSource {
 public:
  virtual ~LevelSource() = default;
  // The encoded bytes of one level, exactly as the world file stores them. Throws Error naming
  // the file, the object and the level when the source is damaged or lacks them.
  virtual std::vector<uint8_t> read_level(ObjectId id, uint32_t level) const = 0;
  // The most bytes the source holds beside the world's directory and the encoded level it
  // returns, whatever it reads (caches, connections, its own copy of a level while reading).
  // GeometryStore reserves it in the run's budget for as long as it lives.
  virtual uint64_t resident_bound() const = 0;
  // The file it reads, for messages and reports.
  virtual const std::string& path() const = 0;
};

// The world file itself: holds nothing beyond the world's directory. `world` must outlive it.
std::unique_ptr<LevelSource> world_level_source(const World& world);

// objects_db "" = the world file; otherwise the object database at that path, opened and checked
// against `world` (a database of another world is refused). `world` must outlive it.
std::unique_ptr<LevelSource> open_level_source(const World& world, const std::string& objects_db);

// resident_bound() of what open_level_source(world, objects_db) opens, without opening it: for
// sizing a budget before a store exists (GeometryStore::fixed_bytes).
uint64_t level_source_bound(const World& world, const std::string& objects_db);

}  // namespace cellwalk
