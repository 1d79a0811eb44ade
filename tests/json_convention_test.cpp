// Issue 16, item 6: one --json convention (docs/json.md). Every reporting command prints one
// object with the schema version and its name; the file read is "input", the file written
// "output"; walk and compare always give a list of runs.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace cellwalk {
namespace {

nlohmann::json json_of_command(const std::string& args) {
  const test::CommandResult r = test::run_cellwalk(args + " --json");
  EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
  const nlohmann::json j = test::json_output(r);
  EXPECT_TRUE(j.is_object()) << args << ": not one JSON object\n" << r.output;
  return j;
}

TEST(JsonConvention, EveryCommandGivesSchemaCommandInputAndOutput) {
  test::TempDir dir;
  const std::string scene = dir.file("c.cwscene"), world = dir.file("c.cww"), path = dir.file("c.path");
  struct Expect {
    std::string args, command, input, output;
  };
  const Expect runs[] = {
      {"generate city --objects 30 --landmark-fraction 0 -o " + scene, "generate", "", scene},
      {"build " + scene + " -o " + world, "build", scene, world},
      {"info " + world, "info", world, ""},
      {"verify " + world, "verify", world, ""},
      {"path " + world + " --frames 12 -o " + path, "path", world, path},
      {"render " + world + " --width 64 --height 48 -o " + dir.file("r.png"), "render", world, dir.file("r.png")},
      {"db " + world + " -o " + dir.file("c.sqlite"), "db", world, dir.file("c.sqlite")},
  };
  for (const Expect& e : runs) {
    const nlohmann::json j = json_of_command(e.args);
    EXPECT_EQ(j.value("schema", 0), 1) << e.args;
    EXPECT_EQ(j.value("command", ""), e.command) << e.args;
    if (!e.input.empty()) {
      EXPECT_EQ(j.value("input", ""), e.input) << e.args;
    }
    if (!e.output.empty()) {
      EXPECT_EQ(j.value("output", ""), e.output) << e.args;
    }
  }
  const nlohmann::json imported = json_of_command("import " + test::cgal_mesh("cow.off") + " -o " + dir.file("i.cwscene"));
  EXPECT_EQ(imported["inputs"], nlohmann::json::array({test::cgal_mesh("cow.off")}));
  // One strategy or two: always a list of runs.
  for (const std::string strategies : {" --strategy brute", " --strategy brute --strategy lod"}) {
    for (const std::string command : {"walk", "compare"}) {
      const nlohmann::json j = json_of_command(command + " " + world + " --path " + path + strategies +
                                               " --width 64 --height 48 -o " + dir.file(command));
      EXPECT_EQ(j.value("command", ""), command);
      EXPECT_EQ(j.value("path", ""), path);
      ASSERT_TRUE(j.contains("runs") && j["runs"].is_array()) << j;
      EXPECT_EQ(j["runs"].size(), strategies.find("lod") != std::string::npos ? 2u : 1u);
      EXPECT_EQ(j["runs"][0]["strategy"], "brute");
    }
  }
}

}  // namespace
}  // namespace cellwalk
