// cellwalk db: the object database of a world (Li & Chiang's objects in a DBMS, fetched per
// object): every level in an SQLite file beside the world, for `walk --objects-db` and
// `bench lichiang --backend sqlite` (docs/format.md, "Object database").
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "cellwalk/store/object_database.hpp"
#include "cellwalk/store/world.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_db(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "db", "Build the object database of a world (SQLite, one row per object and level)");
  struct Args {
    std::string world, out;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("world", a->world, "World file (.cww)")->required();
  cmd->add_option("-o,--output", a->out,
                  "Database file (default: WORLD.sqlite, e.g. city.cww.sqlite)");
  cmd->add_flag("--json", a->json, "Print the summary as JSON");
  cmd->callback([a] {
    const std::string out = a->out.empty() ? default_object_database_path(a->world) : a->out;
    refuse_same_files({a->world}, {out});
    const World world(a->world);
    std::unique_ptr<Progress> progress;
    const ObjectDatabaseBuild built =
        build_object_database(world, out, [&](uint64_t done, uint64_t total) {
          if (!progress) progress = std::make_unique<Progress>("db", total);
          progress->update(done);
        });
    if (progress) progress->finish();
    const ObjectDatabase reopened(world, out);  // checked as a walk will open it
    (void)reopened;
    if (a->json) {
      const nlohmann::ordered_json j = {{"input", a->world},
                                        {"output", out},
                                        {"objects", built.objects},
                                        {"rows", built.rows},
                                        {"blob_bytes", built.blob_bytes},
                                        {"file_bytes", built.file_bytes},
                                        {"seconds", built.seconds}};
      print_json("db", j);
      return;
    }
    std::printf(
        "db: %s: %llu objects, %llu rows (object, level), %llu bytes of levels in a %llu-byte "
        "database, %.1f s\n",
        out.c_str(), static_cast<unsigned long long>(built.objects),
        static_cast<unsigned long long>(built.rows),
        static_cast<unsigned long long>(built.blob_bytes),
        static_cast<unsigned long long>(built.file_bytes), built.seconds);
  });
}

}  // namespace cellwalk::app
