// `cellwalk pvs --show CELL` and `--at X,Y,Z` (issue 15): a user reads back what the engine
// decided for one cell — its box, its state and its visible objects by id and name — exactly as
// the stored sets hold it; and the world keeps the scene's object names (section "names").
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cellwalk/store/world.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// Five boxes in a row along x with names no generator would give (spaces, UTF-8, empty, a tab,
// Latin-1 bytes that are not UTF-8), on a ground slab, so cells see different subsets.
std::vector<Object> named_row() {
  const std::vector<std::string> names = {"ground", "box one", "caja número 2", "", "box\t4", "caf\xe9"};
  std::vector<Object> out;
  for (size_t i = 0; i < names.size(); ++i) {
    Object o;
    o.id = ObjectId(i);
    o.name = names[i];
    const Aabb box = i == 0 ? Aabb{Vec3(-2, -1, -6), Vec3(52, 0, 6)}
                            : Aabb{Vec3(float(i) * 10.0f - 2.0f, 0, 2), Vec3(float(i) * 10.0f + 2.0f, 4, 5)};
    o.mesh = test::box_mesh(box);
    out.push_back(std::move(o));
  }
  return out;
}

nlohmann::json shown(const std::string& args) {
  const test::CommandResult r = test::run_cellwalk(args);
  EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
  const size_t start = r.output.find('{');
  return start == std::string::npos ? nlohmann::json() : nlohmann::json::parse(r.output.substr(start), nullptr, false);
}

TEST(PvsShow, EveryCellReadsBackItsStoredSetWithTheScenesNames) {
  test::TempDir dir;
  const std::vector<Object> objects = named_row();
  const std::string file = test::write_world(dir, objects, NavGraph{}, "row");
  {
    const World world(file);
    std::vector<std::string> expected;
    for (const Object& o : objects) expected.push_back(o.name);
    EXPECT_EQ(world.object_names(), expected);
  }
  ASSERT_EQ(test::run_cellwalk("pvs " + file + " --cells grid:10 --points 8").exit_code, 0);
  const World world(file);
  const visibility::StoredPvs pvs(world);
  ASSERT_GT(pvs.partition().cell_count(), 2u);
  for (CellId c = 0; c < pvs.partition().cell_count(); ++c) {
    SCOPED_TRACE("cell " + std::to_string(c));
    const ViewCell& cell = pvs.partition().cell(c);
    const nlohmann::json j = shown("pvs " + file + " --show " + std::to_string(c) + " --json");
    ASSERT_TRUE(j.is_object());
    EXPECT_EQ(j["cell"], c);
    EXPECT_EQ(j["cells"], pvs.partition().cell_count());
    EXPECT_EQ(j["state"], cell.solid ? "solid" : "computed");
    for (int a = 0; a < 3; ++a) {
      EXPECT_FLOAT_EQ(j["box"]["min"][a].get<float>(), cell.box.min[a]);
      EXPECT_FLOAT_EQ(j["box"]["max"][a].get<float>(), cell.box.max[a]);
    }
    const std::optional<VisibleSet> set = cell.computed() ? pvs.set(c) : std::nullopt;
    const size_t count = set ? set->objects.size() : 0;
    ASSERT_EQ(j["objects"].size(), count);
    for (size_t i = 0; i < count; ++i) {
      EXPECT_EQ(j["objects"][i]["id"], set->objects[i]);
      // JSON carries text: bytes that are not UTF-8 come out as U+FFFD.
      const std::string& name = objects.at(set->objects[i]).name;
      EXPECT_EQ(j["objects"][i]["name"], name == "caf\xe9" ? "caf\xef\xbf\xbd" : name);
    }
    // --at the cell's centre names the same cell.
    const Vec3 centre = (cell.box.min + cell.box.max) * 0.5f;
    const nlohmann::json at = shown("pvs " + file + " --at " + std::to_string(centre.x) + "," + std::to_string(centre.y) +
                                    "," + std::to_string(centre.z) + " --json");
    ASSERT_TRUE(at.is_object());
    EXPECT_EQ(at["cell"], c);
    EXPECT_EQ(at["objects"], j["objects"]);
  }
  // The text form lists every object of the cell's set, one line each, control bytes escaped.
  for (CellId c = 0; c < pvs.partition().cell_count(); ++c) {
    if (!pvs.partition().cell(c).computed()) continue;
    const test::CommandResult text = test::run_cellwalk("pvs " + file + " --show " + std::to_string(c));
    EXPECT_EQ(text.exit_code, 0) << text.output;
    EXPECT_NE(text.output.find("cell " + std::to_string(c) + " of"), std::string::npos) << text.output;
    const std::optional<VisibleSet> set = pvs.set(c);
    for (const ObjectId o : set->objects) {
      const std::string& name = objects.at(o).name;
      const std::string shown_name = name.empty() ? "(no name)" : name == "box\t4" ? "box\\x094" : name;
      EXPECT_NE(text.output.find(std::to_string(o) + "  " + shown_name + "\n"), std::string::npos) << text.output;
    }
  }
}

// A world built before names were kept has none, and a world of no objects keeps no section.
TEST(PvsShow, WorldsWithoutNamesShowEmptyOnes) {
  const World old(test::source_path("tests/data/seeds/cube.cww"));
  EXPECT_EQ(old.object_names(), std::vector<std::string>(old.object_count()));
  test::TempDir dir;
  const World none(test::write_world(dir, {}, NavGraph{}, "empty"));
  EXPECT_EQ(none.object_count(), 0u);
  EXPECT_TRUE(none.object_names().empty());
}

TEST(PvsShow, ACellOrPointThatIsNotThereIsOneLineNamingIt) {
  test::TempDir dir;
  const std::string file = test::write_world(dir, named_row(), NavGraph{}, "row");
  const test::CommandResult none = test::run_cellwalk("pvs " + file + " --show 0");
  EXPECT_NE(none.exit_code, 0);
  EXPECT_NE(none.output.find("no visible sets yet"), std::string::npos) << none.output;
  ASSERT_EQ(test::run_cellwalk("pvs " + file + " --cells grid:10 --points 4").exit_code, 0);
  for (const char* args : {"--show 99999", "--at 1e6,0,0", "--at 1,2", "--at 1,2,nan", "--show 1 --check 2",
                                  "--show 1 --at 0,0,0", "--show 1 --cells grid:5", "--at 0,0,0 -o x.cww"}) {
    SCOPED_TRACE(args);
    const test::CommandResult r = test::run_cellwalk("pvs " + file + " " + std::string(args));
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }
  const test::CommandResult past = test::run_cellwalk("pvs " + file + " --show 99999");
  EXPECT_NE(past.output.find("cells 0 to"), std::string::npos) << past.output;
}

}  // namespace
}  // namespace cellwalk
