// Seed 004 (Zheng) ch. 4–6 as a strategy: `walk` and `compare` run the VDR client over its own
// server like any other strategy; its picture follows τ; a model that is not the world's, a
// missing model and bad settings are refused with one line; the thesis's paths as `path` kinds.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/vdr_client/vdr_strategy.hpp"
#include "test_support.hpp"

namespace cellwalk {
namespace {

// The cow imported as a world and built as a VDR model, with the thesis's orbit around it.
class VdrStrategyTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    for (const std::string& c : {"import " + test::cgal_mesh("cow.off") + " -o " + dir_->file("cow.cwscene"),
                                 "build " + dir_->file("cow.cwscene") + " -o " + dir_->file("cow.cww"),
                                 "vdr-build " + test::cgal_mesh("cow.off") + " -o " + dir_->file("cow.cwvdr") + " --base-triangles 200",
                                 "vdr-build " + test::cgal_mesh("bunny00.off") + " -o " + dir_->file("bunny.cwvdr") +
                                     " --base-triangles 200",
                                 "path " + dir_->file("cow.cww") + " --kind orbit -o " + dir_->file("orbit.path")}) {
      const test::CommandResult r = test::run_cellwalk(c);
      ASSERT_EQ(r.exit_code, 0) << c << ": " << r.output;
    }
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string file(const std::string& name) { return dir_->file(name); }
  static inline test::TempDir* dir_ = nullptr;
  const std::string lens = " --near 0.01 --far 100 --width 96 --height 72 --flat-background";
};

// The orbit path goes round the world's bounds and looks at its centre; the scan has 180 frames.
TEST_F(VdrStrategyTest, ThesisPathsAreKindsOfPath) {
  const CameraPath orbit = read_path(file("orbit.path"));
  ASSERT_EQ(orbit.frames.size(), 194u);
  const test::CommandResult r = test::run_cellwalk("path " + file("cow.cww") + " --kind scan -o " + file("scan.path"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_path(file("scan.path")).frames.size(), 180u);
  EXPECT_GT(glm::distance(orbit.frames[0].position, orbit.frames[100].position), 0.1f);
}

// walk: the client refines from the base mesh (start-up primes it) and reports its counters;
// unpaced frames outrun the 10 ms round trip, so there are fewer batches than frames.
TEST_F(VdrStrategyTest, WalkStreamsTheModel) {
  const test::CommandResult r = test::run_cellwalk("walk " + file("cow.cww") + " --path " + file("orbit.path") +
                                                   " --strategy vdr:latency_ms=5,pace=0 --json -o " + file("walk") + lens);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = test::only_run(r);
  const nlohmann::json& run = j.is_array() ? j[0] : j.contains("runs") ? j["runs"][0] : j;
  ASSERT_TRUE(run.contains("strategy_counters")) << r.output;
  const nlohmann::json& c = run["strategy_counters"];
  EXPECT_GT(c["batches"].get<double>(), 50.0) << r.output;  // start-up's, and one a frame while fewer than f are pending
  EXPECT_GE(c["largest_span"].get<double>(), 1.0) << r.output;
  EXPECT_GT(c["startup_ms"].get<double>(), 0.0) << r.output;
  EXPECT_GT(c["triangles"].get<double>(), 400.0) << r.output;  // refined past the 200-triangle base
  EXPECT_GT(c["bytes_received"].get<double>(), 10000.0) << r.output;
}

// compare: the client's picture against the full model's; a finer τ draws it closer.
TEST_F(VdrStrategyTest, ComparedPictureFollowsTau) {
  double psnr[2] = {0, 0};
  int k = 0;
  for (const std::string tau : {"0.0005", "0.05"}) {
    const test::CommandResult r = test::run_cellwalk("compare " + file("cow.cww") + " --path " + file("orbit.path") +
                                                     " --strategy vdr:pace=0,tau=" + tau + " --every 8 --images 0 --json -o " +
                                                     file("cmp" + tau) + lens);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = test::only_run(r);
    ASSERT_TRUE(j.is_object()) << r.output;
    const nlohmann::json& s = j.contains("summary") ? j["summary"] : j.contains("runs") ? j["runs"][0] : j;
    ASSERT_TRUE(s.contains("mean_psnr_db")) << r.output;
    EXPECT_EQ(s["missed_objects"].get<uint64_t>(), 0u) << r.output;  // the one object is drawn, under its id
    psnr[k++] = s["mean_psnr_db"].is_number() ? s["mean_psnr_db"].get<double>() : 1e9;
  }
  EXPECT_GT(psnr[0], psnr[1] + 1.0) << "τ 0.05 % gave " << psnr[0] << " dB, τ 5 % " << psnr[1] << " dB";
}

// Another model than the world's, a missing one and a memory budget are refused with one line.
TEST_F(VdrStrategyTest, WrongMissingModelsAndBudgetsAreRefused) {
  const std::string walk = "walk " + file("cow.cww") + " --path " + file("orbit.path") + " -o " + file("bad") + lens;
  for (const auto& [strategy, why] : std::vector<std::pair<std::string, std::string>>{
           {"vdr:model=" + file("bunny.cwvdr"), "is not this world's model"},
           {"vdr:model=" + file("none.cwvdr"), "no such VDR model"},
           {"vdr:pace=0 --budget 64", "takes no memory budget"},
           {"vdr:server=127.0.0.1:1", "cannot connect"}}) {
    const test::CommandResult r = test::run_cellwalk(walk + " --strategy " + strategy);
    EXPECT_NE(r.exit_code, 0) << strategy;
    EXPECT_NE(r.output.find(why), std::string::npos) << strategy << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << strategy << ": " << r.output;
  }
}

TEST(VdrStrategyName, SettingsParseAndBadOnesAreRefused) {
  const VdrStrategyConfig ours = parse_vdr_strategy_name("vdr");
  EXPECT_TRUE(ours.ours);
  EXPECT_TRUE(ours.client.gradual_fill);
  EXPECT_GT(ours.client.jump_catch_up, 0u);
  EXPECT_EQ(ours.client.predictor, vdr::Predictor::kTurn);
  const VdrStrategyConfig thesis = parse_vdr_strategy_name("vdr:client=thesis,predictor=linear,span=4,ops=300,server=h:7000");
  EXPECT_FALSE(thesis.client.server_budget);
  EXPECT_EQ(thesis.client.jump_catch_up, 0u);
  EXPECT_FALSE(thesis.client.adaptive_span);
  EXPECT_EQ(thesis.client.span, 4u);
  EXPECT_EQ(thesis.client.n, 300u);
  EXPECT_EQ(thesis.port, 7000);
  for (const std::string bad : {"vdr:client=best", "vdr:span=0", "vdr:span=often", "vdr:ops=70000", "vdr:tau=2",
                                "vdr:server=7000", "vdr:server=h:1,latency_ms=5", "vdr:traversal=random", "vdr:colour=red"}) {
    try {
      parse_vdr_strategy_name(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace cellwalk
