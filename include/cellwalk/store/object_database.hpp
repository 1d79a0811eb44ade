// An object database: a world's encoded levels in an SQLite database beside the world file, one
// row per (object, level), each read with one prepared query, as Li & Chiang's seed (003) kept its
// objects in a DBMS and fetched them one object at a time over JDBC. It exists so that the cost of
// a per-object query path is measured beside the world file's pages (`cellwalk bench lichiang`).
// `cellwalk db WORLD` builds it; docs/format.md ("Object database") gives the schema.
#pragma once

#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

#include "cellwalk/store/level_source.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace cellwalk {

// SQLite's page cache for one open database: PRAGMA cache_size. Reads beyond it go to the
// operating system's page cache, as the world file's do.
constexpr uint64_t kObjectDatabaseCacheBytes = 1 << 20;
// What an open connection holds beside its page cache, at most: the connection, the schema, two
// prepared statements and SQLite's lookaside buffers. Measured on a 1,000-object city, SQLite's
// whole heap peaked at 1,388 KiB against a bound (bound()) of 1,858 KiB; the test
// ObjectDatabaseCity.HeapStaysWithinTheReservedBound checks it.
constexpr uint64_t kObjectDatabaseOverheadBytes = 512 << 10;

// WORLD.sqlite beside the world: "city.cww" -> "city.cww.sqlite".
std::string default_object_database_path(const std::string& world_file);

// Reads levels from an object database built from `world`.
// Thread-safety: read_level is serialised on the one connection (as the seed's one JDBC
// connection was); the other methods are const and safe.
class ObjectDatabase final : public LevelSource {
 public:
  // Opens `path` read-only. Throws Error, with what to do, when it is missing, not an SQLite
  // database, not an object database of this version, or built from another world (its object
  // and level counts or the hash of the world's directory differ).
  ObjectDatabase(const World& world, std::string path);
  ~ObjectDatabase() override;
  ObjectDatabase(const ObjectDatabase&) = delete;
  ObjectDatabase& operator=(const ObjectDatabase&) = delete;

  // One row by its primary key; the blob's size and XXH3-64 are checked against the directory
  // and the row before the bytes are returned.
  std::vector<uint8_t> read_level(ObjectId id, uint32_t level) const override;
  uint64_t resident_bound() const override { return bound(world_); }
  const std::string& path() const override { return path_; }

  // What one open database over `world` holds at most: the page cache, the overhead and SQLite's
  // own copy of the world's largest level while it is read.
  static uint64_t bound(const World& world);
  // SQLite's heap in this process (every connection): the most it held since the last reset, then
  // reset to what it holds now (sqlite3_memory_highwater).
  static uint64_t heap_highwater_and_reset();

 private:
  const World& world_;
  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* read_ = nullptr;
  mutable std::mutex mutex_;

  [[noreturn]] void fail_sqlite(const std::string& where, int rc, const std::string& doing) const;
  // Throws unless the schema is exactly what `cellwalk db` writes.
  void check_schema() const;
};

struct ObjectDatabaseBuild {
  uint64_t objects = 0;
  uint64_t rows = 0;        // one per (object, level)
  uint64_t blob_bytes = 0;  // the levels' encoded bytes, as in the world file
  uint64_t file_bytes = 0;  // of the database
  double seconds = 0.0;
};

// Writes the object database of `world` to `out`: to a temporary beside it, synced and renamed
// into place, so an existing file at `out` is replaced only by a complete database. Every level
// is read through the world file's verified pages. Called with (objects done, objects total).
ObjectDatabaseBuild build_object_database(
    const World& world, const std::string& out,
    const std::function<void(uint64_t, uint64_t)>& progress = {});

}  // namespace cellwalk
