// The store's object database (Li & Chiang's objects in a DBMS, fetched per object): every level
// read through SQLite is the world file's bytes; strategies draw the same with either source; a
// database of another world, an old one or a damaged one is refused with one clear error; what
// SQLite holds stays within what the store reserves for it.
#include "cellwalk/store/object_database.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/runtime/strategies.hpp"
#include "cellwalk/store/geometry_store.hpp"
#include "cellwalk/store/world.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// The message of the Error `f` throws, or "" when it throws none.
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Reads every level of `world` from `db` and checks each against the world file's bytes.
void expect_every_level_equal(const World& world, const ObjectDatabase& db) {
  for (ObjectId id = 0; id < world.object_count(); ++id)
    for (uint32_t level = 0; level < world.object(id).lod_count; ++level)
      ASSERT_EQ(db.read_level(id, level), world.read_level(id, level))
          << "object " << id << " level " << level;
}

void execute(const std::string& db, const std::string& sql) {
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &h), SQLITE_OK);
  char* message = nullptr;
  const int rc = sqlite3_exec(h, sql.c_str(), nullptr, nullptr, &message);
  EXPECT_EQ(rc, SQLITE_OK) << sql << ": " << (message ? message : "");
  sqlite3_free(message);
  sqlite3_close(h);
}

TEST(ObjectDatabase, EveryLevelEqualsTheWorldFilesBytes) {
  const test::TempDir dir;
  const World world(test::write_street_world(dir, 24));
  const std::string db_path = default_object_database_path(world.file().path());
  EXPECT_EQ(db_path, world.file().path() + ".sqlite");
  const ObjectDatabaseBuild built = build_object_database(world, db_path);
  uint64_t levels = 0;
  for (ObjectId id = 0; id < world.object_count(); ++id) levels += world.object(id).lod_count;
  EXPECT_EQ(built.objects, world.object_count());
  EXPECT_EQ(built.rows, levels);
  EXPECT_GT(built.file_bytes, built.blob_bytes);
  const ObjectDatabase db(world, db_path);
  expect_every_level_equal(world, db);
  // Through the store: the same decoded meshes from either source.
  GeometryStore from_file(world, 0),
      from_db(world, 0, nullptr, 1, open_level_source(world, db_path));
  EXPECT_EQ(from_db.source().path(), db_path);
  FetchStats a, b;
  for (ObjectId id = 0; id < world.object_count(); ++id) {
    const auto m = from_file.get(id, 0, {}, a), n = from_db.get(id, 0, {}, b);
    EXPECT_EQ(m->positions, n->positions);
    EXPECT_EQ(m->indices, n->indices);
  }
  EXPECT_EQ(a.bytes_read, b.bytes_read);
  EXPECT_EQ(a.cache_misses, b.cache_misses);
}

TEST(ObjectDatabase, RefusesADatabaseOfAnotherWorldOrVersion) {
  const test::TempDir dir;
  const World world(test::write_street_world(dir, 12, 1));
  const test::TempDir other_dir;
  const World same_count(test::write_street_world(other_dir, 12, 2));  // other boxes, same count
  const std::string db = dir.file("objects.sqlite");
  build_object_database(world, db);
  for (const World* other : {&same_count}) {
    const std::string message = error_of([&] { ObjectDatabase(*other, db); });
    EXPECT_NE(message.find("another world"), std::string::npos) << message;
    EXPECT_NE(message.find("rebuild it with `cellwalk db " + other->file().path() + "`"),
              std::string::npos)
        << message;
  }
  const test::TempDir third;
  const World more(test::write_street_world(third, 13, 1));
  EXPECT_NE(error_of([&] { ObjectDatabase(more, db); }).find("another world"), std::string::npos);
  execute(db, "UPDATE meta SET value = 0 WHERE key = 'version'");
  const std::string old = error_of([&] { ObjectDatabase(world, db); });
  EXPECT_NE(old.find("version 0"), std::string::npos) << old;
}

// Each damage gives one Error naming the file (and, for a row, the object and level) and saying
// what to do; never a crash, never wrong bytes.
TEST(ObjectDatabase, DamagedDatabasesGiveOneClearError) {
  const test::TempDir dir;
  const World world(test::write_street_world(dir, 12));
  const std::string good = dir.file("good.sqlite"), db = dir.file("db.sqlite");
  build_object_database(world, good);
  auto fresh = [&] {
    std::filesystem::copy_file(good, db, std::filesystem::copy_options::overwrite_existing);
  };
  // Opening or reading every level fails with one line naming `db` and containing `says`.
  auto expect_refused = [&](const std::string& says) {
    const std::string message = error_of([&] {
      const ObjectDatabase d(world, db);
      for (ObjectId id = 0; id < world.object_count(); ++id)
        for (uint32_t level = 0; level < world.object(id).lod_count; ++level)
          d.read_level(id, level);
    });
    EXPECT_EQ(message.rfind(db, 0), 0u) << message;
    EXPECT_NE(message.find(says), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  };
  std::filesystem::remove(db);
  expect_refused("cellwalk db");  // missing
  test::spit(db, {});
  expect_refused("not a cellwalk object database");  // empty: SQLite sees an empty database
  test::spit(db, test::slurp(world.file().path()));
  expect_refused("rebuild it with");  // not an SQLite file
  fresh();
  execute(db, "DROP TABLE levels");
  expect_refused("not a cellwalk object database");
  // Hostile schemas: a view in place of a table (one that never ends) or a table of its own.
  fresh();
  execute(db, "DROP TABLE meta; CREATE VIEW meta(key, value) AS WITH RECURSIVE r(x) AS (SELECT 1 UNION ALL "
              "SELECT x + 1 FROM r) SELECT 'k', x FROM r");
  expect_refused("a view \"meta\"");
  fresh();
  execute(db, "CREATE TABLE extra(x)");
  expect_refused("a table \"extra\"");
  // Two rows' keys swapped: each key finds the other's bytes, which its hash refuses.
  fresh();
  execute(db, "UPDATE levels SET object = -1 WHERE object = 2 AND level = 0; "
              "UPDATE levels SET object = 2 WHERE object = 3 AND level = 0; "
              "UPDATE levels SET object = 3 WHERE object = -1 AND level = 0");
  expect_refused("object 2 level 0: the row");
  fresh();
  execute(db, "DELETE FROM levels WHERE object = 3 AND level = 0");
  expect_refused("object 3 level 0: no such row");
  fresh();
  execute(db, "UPDATE levels SET bytes = zeroblob(7) WHERE object = 2 AND level = 0");
  expect_refused("object 2 level 0: the row holds 7 bytes");
  fresh();
  execute(db, "UPDATE levels SET bytes = CAST(bytes AS TEXT) WHERE object = 1 AND level = 0");
  expect_refused("object 1 level 0");
  fresh();
  execute(db, "UPDATE levels SET hash = hash + 1 WHERE object = 5 AND level = 0");
  expect_refused("object 5 level 0: the row's bytes do not match its hash");
  // Truncated to a fraction of its pages.
  for (double keep : {0.5, 0.1}) {
    std::vector<uint8_t> bytes = test::slurp(good);
    bytes.resize(static_cast<size_t>(bytes.size() * keep));
    test::spit(db, bytes);
    expect_refused("rebuild it with");
  }
}

// A byte flipped anywhere: every level read is the world's or the read throws Error.
TEST(ObjectDatabase, FlippedBytesNeverGiveOtherBytes) {
  const test::TempDir dir;
  const World world(test::write_street_world(dir, 12));
  const std::string good = dir.file("good.sqlite"), db = dir.file("db.sqlite");
  build_object_database(world, good);
  const std::vector<uint8_t> bytes = test::slurp(good);
  int refused = 0, intact = 0;
  for (size_t at = 0; at < bytes.size(); at += 97) {
    std::vector<uint8_t> damaged = bytes;
    damaged[at] ^= 0x5a;
    test::spit(db, damaged);
    try {
      const ObjectDatabase d(world, db);
      for (ObjectId id = 0; id < world.object_count(); ++id)
        for (uint32_t level = 0; level < world.object(id).lod_count; ++level)
          ASSERT_EQ(d.read_level(id, level), world.read_level(id, level)) << "byte " << at;
      ++intact;
    } catch (const Error&) {
      ++refused;
    }
  }
  EXPECT_GT(refused, 0);
  EXPECT_GT(intact, 0);  // flips in free space and unused header bytes change nothing
}

// A city whose database is larger than SQLite's page cache, with stored sets and a path.
class ObjectDatabaseCity : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    inputs_ = new test::SharedInputs(
        "database-city", {"generate city --objects 150 --landmark-fraction 0.2 --seed 6 -o {dir}/city.cwscene",
                          "build {dir}/city.cwscene -o {dir}/city.cww",
                          "pvs {dir}/city.cww --engine conservative --cells grid:25",
                          "path {dir}/city.cww --frames 40 --seed 4 -o {dir}/city.path", "db {dir}/city.cww"});
    world_ = inputs_->file("city.cww");
    path_ = inputs_->file("city.path");
    db_ = world_ + ".sqlite";
  }
  static void TearDownTestSuite() { delete inputs_; }
  static inline test::SharedInputs* inputs_ = nullptr;
  static inline std::string world_, path_, db_;
  const test::TempDir out_;  // this test's outputs
};

// SQLite's heap, measured by SQLite, never passes what the store reserves for the database
// while every level is read twice (the cache full and cycling).
TEST_F(ObjectDatabaseCity, HeapStaysWithinTheReservedBound) {
  const World world(world_);
  ASSERT_GT(std::filesystem::file_size(db_), 2 * kObjectDatabaseCacheBytes);  // the cache fills
  ObjectDatabase::heap_highwater_and_reset();
  const uint64_t before =
      ObjectDatabase::heap_highwater_and_reset();  // what other connections hold
  {
    const ObjectDatabase db(world, db_);
    for (int pass = 0; pass < 2; ++pass) expect_every_level_equal(world, db);
  }
  const uint64_t peak = ObjectDatabase::heap_highwater_and_reset();
  EXPECT_LE(peak - before, ObjectDatabase::bound(world));
  EXPECT_GT(peak - before, kObjectDatabaseCacheBytes / 2);  // the measure sees the cache
}

// The same path, the same strategies, the same budget: the same items, the same geometry and
// (without a prefetching thread, whose timing varies) the same hits and misses from either source.
TEST_F(ObjectDatabaseCity, StrategiesDrawTheSameFromEitherSource) {
  const World world(world_);
  const CameraPath path = read_path(path_);
  for (const std::string name : {"brute", "lichiang:cache=lru,prefetch=none", "lichiang"}) {
    SCOPED_TRACE(name);
    StrategyOptions file_options;
    file_options.memory_budget_bytes = 24 << 20;
    StrategyOptions db_options = file_options;
    db_options.objects_db = db_;
    const std::unique_ptr<Strategy> a = make_strategy(name, world, file_options),
                                    b = make_strategy(name, world, db_options);
    std::vector<DrawItem> ia, ib;
    FrameStats sa, sb;
    Camera camera;
    for (const PathFrame& f : path.frames) {
      apply(f, camera);
      a->select(camera, ia, sa);
      b->select(camera, ib, sb);
      ASSERT_EQ(ia.size(), ib.size());
      for (size_t i = 0; i < ia.size(); ++i) {
        ASSERT_EQ(ia[i].id, ib[i].id);
        ASSERT_EQ(ia[i].lod, ib[i].lod);
        const Mesh* ma = a->mesh(ia[i], sa);
        const Mesh* mb = b->mesh(ib[i], sb);
        ASSERT_EQ(ma == nullptr, mb == nullptr);
        if (ma) {
          ASSERT_EQ(ma->positions, mb->positions);
          ASSERT_EQ(ma->indices, mb->indices);
        }
      }
    }
    EXPECT_GT(sa.cache_misses, 0u);
    if (name != "lichiang") {
      EXPECT_EQ(sa.cache_hits, sb.cache_hits);
      EXPECT_EQ(sa.cache_misses, sb.cache_misses);
      EXPECT_EQ(sa.bytes_read, sb.bytes_read);
    }
    EXPECT_LE(b->peak_resident_bytes(), db_options.memory_budget_bytes);
  }
}

// From the command line: compare gives the same images against ground truth from either source;
// a walk over the database holds its budget (the strategy's count, and the process's peak beside
// the baseline); a database of another world is refused by walk with what to do.
TEST_F(ObjectDatabaseCity, WalkAndCompareOverTheDatabase) {
  for (const std::string strategy : {"brute", "lichiang"}) {
    SCOPED_TRACE(strategy);
    nlohmann::json runs[2];
    for (int with_db = 0; with_db < 2; ++with_db) {
      const test::CommandResult r =
          test::run_cellwalk("compare " + world_ + " --path " + path_ + " --strategy " + strategy +
                             (with_db ? " --objects-db " + db_ : std::string()) +
                             " --every 4 --width 128 --height 96 --json -o " + out_.file("cmp"));
      ASSERT_EQ(r.exit_code, 0) << r.output;
      runs[with_db] = test::only_run(r);
      ASSERT_TRUE(runs[with_db].is_object()) << r.output;
    }
    const nlohmann::json& a = runs[0].contains("strategies") ? runs[0]["strategies"][0] : runs[0];
    const nlohmann::json& b = runs[1].contains("strategies") ? runs[1]["strategies"][0] : runs[1];
    for (const char* key :
         {"mean_differing_fraction", "max_differing_fraction", "visible_objects", "missed_objects"})
      EXPECT_EQ(a[key], b[key]) << key;
  }
  const test::CommandResult r = test::run_cellwalk(
      "walk " + world_ + " --path " + path_ +
      " --strategy lichiang:cache=lru,prefetch=none --objects-db " + db_ +
      " --budget 24 --gpu-budget 1 --width 128 --height 96 --json -o " + out_.file("walk"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = test::only_run(r);
  ASSERT_TRUE(j.is_object()) << r.output;
  EXPECT_GT(j["cache_misses"].get<uint64_t>(), 0u);
  EXPECT_LE(j["peak_resident_bytes"].get<uint64_t>(), j["strategy_budget_bytes"].get<uint64_t>());
  if (!test::kUnderAddressSanitizer) {
    EXPECT_LE(j["peak_rss_bytes"].get<uint64_t>(),
              j["budget_bytes"].get<uint64_t>() + j["baseline_rss_bytes"].get<uint64_t>());
  }

  const test::TempDir other;
  const std::string other_world = test::write_street_world(other, 12);
  const test::CommandResult refused =
      test::run_cellwalk("walk " + other_world + " --path " + path_ +
                         " --strategy brute --objects-db " + db_ + " -o " + other.file("w"));
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.output.find("rebuild it with `cellwalk db " + other_world + "`"),
            std::string::npos)
      << refused.output;
}

// cellwalk db: the default file beside the world, --json, and never over its own input.
TEST_F(ObjectDatabaseCity, DbCommand) {
  test::CommandResult r = test::run_cellwalk("db " + world_ + " -o " + world_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(std::filesystem::exists(world_));
  EXPECT_NO_THROW(World{world_});
  r = test::run_cellwalk("db " + world_ + " --json -o " + out_.file("copy.sqlite"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = test::json_output(r);
  ASSERT_TRUE(j.is_object()) << r.output;
  EXPECT_EQ(j["objects"].get<uint64_t>(), 150u);
  EXPECT_EQ(j["file_bytes"].get<uint64_t>(), std::filesystem::file_size(out_.file("copy.sqlite")));
  r = test::run_cellwalk("db --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("--output"), std::string::npos);
}

}  // namespace
}  // namespace cellwalk
