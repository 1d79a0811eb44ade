// Li & Chiang (seed 003), "objects stored in a DBMS, fetched per object over JDBC": the store's
// object database, an SQLite file of the world's encoded levels (docs/format.md, "Object
// database").
#include "cellwalk/store/object_database.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <type_traits>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/store/world.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk {
namespace {

constexpr const char* kFormat = "cellwalk objects";
constexpr int64_t kVersion = 1;

// What ties a database to its world: the directory the levels were read by (every object's box,
// colour and level count, every level's size, triangles and error), hashed in id order. Not the
// levels' offsets: `pvs --engine vlod` moves levels within the world file without changing them.
uint64_t directory_hash(const World& world) {
  XXH3_state_t* state = XXH3_createState();
  XXH3_64bits_reset(state);
  for (ObjectId id = 0; id < world.object_count(); ++id) {
    const ObjectRecord& o = world.object(id);
    const float box[6] = {o.bounds.min.x, o.bounds.min.y, o.bounds.min.z,
                          o.bounds.max.x, o.bounds.max.y, o.bounds.max.z};
    XXH3_64bits_update(state, box, sizeof(box));
    XXH3_64bits_update(state, &o.color, sizeof(o.color));
    XXH3_64bits_update(state, &o.lod_count, sizeof(o.lod_count));
    for (uint32_t level = 0; level < o.lod_count; ++level) {
      const LodRecord& l = world.lod(id, level);
      const uint32_t fields[2] = {l.bytes, l.triangles};
      XXH3_64bits_update(state, fields, sizeof(fields));
      XXH3_64bits_update(state, &l.error, sizeof(l.error));
    }
  }
  const uint64_t hash = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  return hash;
}

// A row's hash is seeded with its key, so the bytes of one (object, level) under another's key
// (a hostile edit, or keys swapped by damage) do not match.
uint64_t row_hash(const std::vector<uint8_t>& bytes, ObjectId id, uint32_t level) {
  return XXH3_64bits_withSeed(bytes.data(), bytes.size(), (uint64_t(id) << 32) | level);
}

uint64_t level_count(const World& world) {
  uint64_t n = 0;
  for (ObjectId id = 0; id < world.object_count(); ++id) n += world.object(id).lod_count;
  return n;
}

uint64_t largest_level_bytes(const World& world) {
  uint64_t largest = 0;
  for (ObjectId id = 0; id < world.object_count(); ++id)
    for (uint32_t level = 0; level < world.object(id).lod_count; ++level)
      largest = std::max<uint64_t>(largest, world.lod(id, level).bytes);
  return largest;
}

std::string rebuild_hint(const World& world) {
  return "rebuild it with `cellwalk db " + world.file().path() + "`";
}

// A statement that is finalised whatever happens.
struct Statement {
  sqlite3_stmt* stmt = nullptr;
  ~Statement() { sqlite3_finalize(stmt); }
};

void fsync_path(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags);
  if (fd < 0) fail(path, std::string("cannot open to sync: ") + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0 && !(flags & O_DIRECTORY))
    fail(path, std::string("fsync failed: ") + std::strerror(err));
}

}  // namespace

std::string default_object_database_path(const std::string& world_file) {
  return world_file + ".sqlite";
}

uint64_t ObjectDatabase::bound(const World& world) {
  return kObjectDatabaseCacheBytes + kObjectDatabaseOverheadBytes + largest_level_bytes(world);
}

uint64_t ObjectDatabase::heap_highwater_and_reset() {
  return static_cast<uint64_t>(sqlite3_memory_highwater(1));
}

void ObjectDatabase::fail_sqlite(const std::string& where, int rc, const std::string& doing) const {
  const int primary = rc & 0xff;
  std::string what = doing + ": " + (db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc));
  if (primary == SQLITE_NOTADB || primary == SQLITE_CORRUPT)
    what += " (the database is damaged or is not an object database); " + rebuild_hint(world_);
  else if (primary == SQLITE_TOOBIG)
    what += " (a row is larger than any level of the world: the database is damaged); " +
            rebuild_hint(world_);
  else if (primary == SQLITE_ERROR)
    what += " (not a cellwalk object database of this version); " + rebuild_hint(world_);
  fail(where, what);
}

// Opened read-only with SQLite's defences for files it did not write (a database may be damaged
// or hostile): no memory mapping, cell sizes checked, no schema code trusted, and no value longer
// than the world's largest level (so a damaged row cannot make SQLite allocate more than the
// bound this store reserves).
ObjectDatabase::ObjectDatabase(const World& world, std::string path)
    : world_(world), path_(std::move(path)) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path_, ec))
    fail(path_, "no object database here; build it with `cellwalk db " + world.file().path() +
                    " -o " + path_ + "`");
  int rc =
      sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX, nullptr);
  if (rc != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
    sqlite3_close(db_);
    db_ = nullptr;
    fail(path_, "cannot open the object database: " + message);
  }
  try {
    sqlite3_db_config(db_, SQLITE_DBCONFIG_DEFENSIVE, 1, nullptr);
    sqlite3_db_config(db_, SQLITE_DBCONFIG_TRUSTED_SCHEMA, 0, nullptr);
    sqlite3_limit(db_, SQLITE_LIMIT_LENGTH,
                  static_cast<int>(std::clamp<uint64_t>(largest_level_bytes(world), 4096, INT32_MAX)));
    // Only the two tables `cellwalk db` writes are ever queried, with statements of our own.
    sqlite3_limit(db_, SQLITE_LIMIT_SQL_LENGTH, 4096);
    sqlite3_limit(db_, SQLITE_LIMIT_COMPOUND_SELECT, 2);
    const std::string pragmas =
        "PRAGMA mmap_size=0; PRAGMA cell_size_check=ON; PRAGMA cache_size=-" +
        std::to_string(kObjectDatabaseCacheBytes / 1024) + ";";
    if ((rc = sqlite3_exec(db_, pragmas.c_str(), nullptr, nullptr, nullptr)) != SQLITE_OK)
      fail_sqlite(path_, rc, "setting up the connection");

    check_schema();
    // The metadata: format, version and the world it was built from.
    Statement meta;
    if ((rc = sqlite3_prepare_v2(db_, "SELECT key, value FROM meta LIMIT 16", -1, &meta.stmt, nullptr)) !=
        SQLITE_OK)
      fail_sqlite(path_, rc, "reading its metadata");
    std::string format;
    int64_t version = 0, objects = -1, levels = -1, hash = 0;
    while ((rc = sqlite3_step(meta.stmt)) == SQLITE_ROW) {
      const auto* key = reinterpret_cast<const char*>(sqlite3_column_text(meta.stmt, 0));
      const std::string k = key ? key : "";
      if (k == "format") {
        const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(meta.stmt, 1));
        format = text ? text : "";
      } else if (k == "version") {
        version = sqlite3_column_int64(meta.stmt, 1);
      } else if (k == "world_objects") {
        objects = sqlite3_column_int64(meta.stmt, 1);
      } else if (k == "world_levels") {
        levels = sqlite3_column_int64(meta.stmt, 1);
      } else if (k == "world_directory_hash") {
        hash = sqlite3_column_int64(meta.stmt, 1);
      }
    }
    if (rc != SQLITE_DONE) fail_sqlite(path_, rc, "reading its metadata");
    if (format != kFormat)
      fail(path_, "is not a cellwalk object database (no format row); " + rebuild_hint(world));
    if (version != kVersion)
      fail(path_, "is an object database of version " + std::to_string(version) +
                      ", this cellwalk reads version " + std::to_string(kVersion) + "; " +
                      rebuild_hint(world));
    const uint64_t own_hash = directory_hash(world);
    if (objects != int64_t(world.object_count()) || levels != int64_t(level_count(world)) ||
        static_cast<uint64_t>(hash) != own_hash) {
      char seen[17], own[17];
      std::snprintf(seen, sizeof(seen), "%016llx", static_cast<unsigned long long>(hash));
      std::snprintf(own, sizeof(own), "%016llx", static_cast<unsigned long long>(own_hash));
      fail(path_, "was built from another world (" + std::to_string(objects) + " objects, " +
                      std::to_string(levels) + " levels, directory hash " + seen + ") than " +
                      world.file().path() + " (" + std::to_string(world.object_count()) +
                      " objects, " + std::to_string(level_count(world)) + " levels, hash " + own +
                      "); " + rebuild_hint(world));
    }
    if ((rc = sqlite3_prepare_v3(db_,
                                 "SELECT hash, bytes, object, level FROM levels WHERE object = ?1 AND level = ?2",
                                 -1, SQLITE_PREPARE_PERSISTENT, &read_, nullptr)) != SQLITE_OK)
      fail_sqlite(path_, rc, "preparing the level query");
  } catch (...) {
    sqlite3_finalize(read_);
    sqlite3_close(db_);
    throw;
  }
}

// A hostile file can make `meta` or `levels` a view whose query never ends or fills memory:
// before any other query, the schema must be the two tables `cellwalk db` writes and their
// primary-key indexes, nothing else.
void ObjectDatabase::check_schema() const {
  Statement schema;
  int rc = sqlite3_prepare_v2(db_, "SELECT type, name FROM sqlite_schema LIMIT 8", -1, &schema.stmt, nullptr);
  if (rc != SQLITE_OK) fail_sqlite(path_, rc, "reading its schema");
  int tables = 0, rows = 0;
  while ((rc = sqlite3_step(schema.stmt)) == SQLITE_ROW) {
    ++rows;
    const auto* type = reinterpret_cast<const char*>(sqlite3_column_text(schema.stmt, 0));
    const auto* name = reinterpret_cast<const char*>(sqlite3_column_text(schema.stmt, 1));
    const std::string t = type ? type : "", n = name ? name : "";
    if (t == "table" && (n == "meta" || n == "levels")) ++tables;
    else if (!(t == "index" && n.rfind("sqlite_autoindex_", 0) == 0))
      fail(path_, "holds " + (t.empty() ? "an entry" : "a " + t) + " \"" + n +
                      "\" that no object database has (the file is damaged or not ours); " + rebuild_hint(world_));
  }
  if (rc != SQLITE_DONE) fail_sqlite(path_, rc, "reading its schema");
  if (tables != 2 || rows > 4)
    fail(path_, "is not a cellwalk object database (it needs exactly the tables meta and levels); " + rebuild_hint(world_));
}

ObjectDatabase::~ObjectDatabase() {
  sqlite3_finalize(read_);
  sqlite3_close(db_);
}

std::vector<uint8_t> ObjectDatabase::read_level(ObjectId id, uint32_t level) const {
  const LodRecord& l = world_.lod(id, level);  // throws for a level the world does not have
  const std::string where =
      path_ + ": object " + std::to_string(id) + " level " + std::to_string(level);
  std::lock_guard lock(mutex_);
  struct Reset {
    sqlite3_stmt* stmt;
    ~Reset() { sqlite3_reset(stmt); }
  } reset{read_};
  sqlite3_bind_int64(read_, 1, id);
  sqlite3_bind_int64(read_, 2, level);
  const int rc = sqlite3_step(read_);
  if (rc == SQLITE_DONE) fail(where, "no such row in the object database; " + rebuild_hint(world_));
  if (rc != SQLITE_ROW) fail_sqlite(where, rc, "reading the row");
  // A damaged index can point at another object's row: the row must name what was asked for.
  if (sqlite3_column_int64(read_, 2) != int64_t(id) || sqlite3_column_int64(read_, 3) != int64_t(level))
    fail(where, "the index found the row of object " + std::to_string(sqlite3_column_int64(read_, 2)) + " level " +
                    std::to_string(sqlite3_column_int64(read_, 3)) + " (the database is damaged); " + rebuild_hint(world_));
  if (sqlite3_column_type(read_, 1) != SQLITE_BLOB && l.bytes != 0)
    fail(where,
         "the row's bytes are not a blob (the database is damaged); " + rebuild_hint(world_));
  const auto* blob = static_cast<const uint8_t*>(sqlite3_column_blob(read_, 1));
  const auto size = static_cast<uint64_t>(sqlite3_column_bytes(read_, 1));
  if (size != l.bytes)
    fail(where, "the row holds " + std::to_string(size) + " bytes, the world's directory says " +
                    std::to_string(l.bytes) + " (the database is damaged or stale); " +
                    rebuild_hint(world_));
  std::vector<uint8_t> bytes(blob, blob + size);
  if (row_hash(bytes, id, level) !=
      static_cast<uint64_t>(sqlite3_column_int64(read_, 0)))
    fail(where, "the row's bytes do not match its hash (the database is damaged); " +
                    rebuild_hint(world_));
  return bytes;
}

// Written with no journal and no syncs (it is a temporary until renamed), then synced once.
ObjectDatabaseBuild build_object_database(const World& world, const std::string& out,
                                          const std::function<void(uint64_t, uint64_t)>& progress) {
  Stopwatch watch;
  const std::string temp = temporary_path(out, ::getpid());
  ::unlink(temp.c_str());
  sqlite3* db = nullptr;
  auto check = [&](int rc, const char* doing) {
    if (rc == SQLITE_OK || rc == SQLITE_DONE || rc == SQLITE_ROW) return;
    fail(out, std::string(doing) + ": " + (db ? sqlite3_errmsg(db) : sqlite3_errstr(rc)));
  };
  ObjectDatabaseBuild report;
  try {
    check(
        sqlite3_open_v2(temp.c_str(), &db,
                        SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr),
        "creating the database");
    check(sqlite3_exec(
              db,
              "PRAGMA journal_mode=OFF; PRAGMA synchronous=OFF; PRAGMA page_size=4096;"
              "CREATE TABLE meta(key TEXT PRIMARY KEY NOT NULL, value NOT NULL) WITHOUT ROWID;"
              "CREATE TABLE levels(object INTEGER NOT NULL, level INTEGER NOT NULL,"
              " triangles INTEGER NOT NULL, hash INTEGER NOT NULL, bytes BLOB NOT NULL,"
              " PRIMARY KEY(object, level));"
              "BEGIN;",
              nullptr, nullptr, nullptr),
          "creating the tables");
    {
      Statement insert;
      check(sqlite3_prepare_v2(db, "INSERT INTO levels VALUES (?1, ?2, ?3, ?4, ?5)", -1,
                               &insert.stmt, nullptr),
            "preparing the insert");
      for (ObjectId id = 0; id < world.object_count(); ++id) {
        for (uint32_t level = 0; level < world.object(id).lod_count; ++level) {
          const std::vector<uint8_t> bytes = world.read_level(id, level);
          sqlite3_bind_int64(insert.stmt, 1, id);
          sqlite3_bind_int64(insert.stmt, 2, level);
          sqlite3_bind_int64(insert.stmt, 3, world.lod(id, level).triangles);
          sqlite3_bind_int64(insert.stmt, 4,
                             static_cast<int64_t>(row_hash(bytes, id, level)));
          sqlite3_bind_blob64(insert.stmt, 5, bytes.data(), bytes.size(), SQLITE_STATIC);
          check(sqlite3_step(insert.stmt), "writing a level");
          sqlite3_reset(insert.stmt);
          ++report.rows;
          report.blob_bytes += bytes.size();
        }
        ++report.objects;
        if (progress) progress(id + 1, world.object_count());
      }
      Statement meta;
      check(sqlite3_prepare_v2(db, "INSERT INTO meta VALUES (?1, ?2)", -1, &meta.stmt, nullptr),
            "preparing the metadata");
      auto put = [&](const char* key, auto value) {
        sqlite3_bind_text(meta.stmt, 1, key, -1, SQLITE_STATIC);
        if constexpr (std::is_same_v<decltype(value), const char*>)
          sqlite3_bind_text(meta.stmt, 2, value, -1, SQLITE_TRANSIENT);
        else
          sqlite3_bind_int64(meta.stmt, 2, static_cast<int64_t>(value));
        check(sqlite3_step(meta.stmt), "writing the metadata");
        sqlite3_reset(meta.stmt);
      };
      put("format", kFormat);
      put("version", kVersion);
      put("world_objects", uint64_t(world.object_count()));
      put("world_levels", level_count(world));
      put("world_directory_hash", directory_hash(world));
      put("world_file", world.file().path().c_str());
    }
    check(sqlite3_exec(db, "COMMIT;", nullptr, nullptr, nullptr), "committing");
    check(sqlite3_close(db), "closing");
    db = nullptr;
    fsync_path(temp, O_RDONLY);
    if (::rename(temp.c_str(), out.c_str()) != 0)
      fail(out, std::string("rename failed: ") + std::strerror(errno));
    fsync_path(std::filesystem::path(out).parent_path().empty()
                   ? "."
                   : std::filesystem::path(out).parent_path().string(),
               O_RDONLY | O_DIRECTORY);
  } catch (...) {
    sqlite3_close(db);
    ::unlink(temp.c_str());
    throw;
  }
  report.file_bytes = std::filesystem::file_size(out);
  report.seconds = watch.lap_ms() / 1000.0;
  return report;
}

}  // namespace cellwalk
