// The sweep library's planning (reports/SweepPlan.hpp): the product of the axes,
// points that differ only in ignored settings planned once, axes no point uses
// refused, plan files read back. Generated traces are planned, not generated,
// so these tests need no executable.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "reports/SweepPlan.hpp"

namespace oit::sweep {
namespace {

namespace fs = std::filesystem;

// A spec file in a fresh folder, and its plan into <folder>/out.
class SweepPlanTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("sweep_plan_" + std::to_string(::getpid()) + "_" +
                                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  Plan plan(const std::string& json) {
    const std::string spec = (dir_ / "s.json").string();
    std::ofstream(spec) << json;
    return planSweep(loadSpec(spec), spec, dir_ / "out", "/usr/bin/oitsim");
  }
  std::string planError(const std::string& json) {
    try {
      plan(json);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no error)";
  }
  fs::path dir_;
};

// 3 algorithms x 3 k = 9 combinations; abuffer and wboit ignore k, so each is
// planned once (at the first k): 3 + 1 + 1 = 5 points, 4 duplicates.
TEST_F(SweepPlanTest, AlgorithmsThatIgnoreKArePlannedOnce) {
  const Plan p = plan(R"({"traces": [{"gen": "glass", "width": 32, "height": 24}],
    "base": {"mode": "functional"}, "axes": {"algo": ["mlab", "abuffer", "wboit"], "layers": [2, 4, 8]}})");
  EXPECT_EQ(p.combinations, 9u);
  ASSERT_EQ(p.points.size(), 5u);
  const char* ids[] = {"0000-glass-mlab-2", "0001-glass-mlab-4", "0002-glass-mlab-8", "0003-glass-abuffer-2",
                       "0004-glass-wboit-2"};
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ(p.points[i].id, ids[i]);
  ASSERT_EQ(p.duplicates.size(), 4u);
  EXPECT_EQ(p.duplicates[0].labels, "glass-abuffer-4");
  EXPECT_EQ(p.duplicates[0].same_as, "0003-glass-abuffer-2");
  EXPECT_EQ(p.duplicates[0].ignored, std::vector<std::string>{"layers"});
  EXPECT_EQ(p.duplicates[3].labels, "glass-wboit-8");
  EXPECT_EQ(p.duplicates[3].same_as, "0004-glass-wboit-2");
  EXPECT_EQ(duplicatesLine(p),
            "4 of 9 combinations differ only in settings their algorithm or mode ignores and are planned once "
            "(layers: abuffer, wboit): 5 points");
  // A point's arguments: the run's, with its own output folder.
  const auto& a = p.points[3].args;
  ASSERT_GE(a.size(), 6u);
  EXPECT_EQ(a[0], "run");
  EXPECT_EQ(a[4], (dir_ / "out" / "points" / "0003-glass-abuffer-2").string());
}

// Functional points ignore the ROP configuration: the functional half of a
// speed x cache.ways product is one point, the timing half two.
TEST_F(SweepPlanTest, FunctionalPointsThatDifferOnlyInRopParametersArePlannedOnce) {
  const Plan p = plan(R"({"traces": [{"gen": "glass"}], "base": {"algo": "mlab"},
    "axes": {"speed": [{"label": "functional", "mode": "functional"}, {"label": "timing", "mode": "timing"}],
             "cache.ways": [2, 8]}})");
  ASSERT_EQ(p.points.size(), 3u);
  EXPECT_EQ(p.points[0].id, "0000-glass-functional-2");
  EXPECT_EQ(p.points[1].id, "0001-glass-timing-2");
  EXPECT_EQ(p.points[2].id, "0002-glass-timing-8");
  ASSERT_EQ(p.duplicates.size(), 1u);
  EXPECT_EQ(p.duplicates[0].ignored, std::vector<std::string>{"cache.ways"});
  EXPECT_NE(duplicatesLine(p).find("(cache.ways: functional points)"), std::string::npos) << duplicatesLine(p);
}

TEST_F(SweepPlanTest, AnAxisNoPointUsesIsAnErrorNamingItAndWhy) {
  EXPECT_EQ(planError(R"({"traces": [{"gen": "glass"}], "axes": {"algo": ["abuffer", "wboit"], "layers": [2, 4]}})"),
            "sweep spec " + (dir_ / "s.json").string() +
                ": axes.layers: no point uses this axis (abuffer ignores layers; wboit ignores layers); remove it");
  EXPECT_EQ(planError(R"({"traces": [{"gen": "glass"}], "base": {"mode": "functional"},
    "axes": {"cache.ways": [2, 8]}})"),
            "sweep spec " + (dir_ / "s.json").string() +
                ": axes.cache.ways: no point uses this axis (functional points ignore cache.ways); remove it");
  // A bundle counts as used when any of its settings is.
  EXPECT_EQ(plan(R"({"traces": [{"gen": "glass"}], "base": {"algo": "abuffer", "mode": "functional"},
    "axes": {"b": [{"label": "x", "layers": 2, "background": [1, 0, 0]}]}})").points.size(),
            1u);
}

TEST_F(SweepPlanTest, PlanFilesReadBackAndCommandsReproduceEachPoint) {
  const Plan p = plan(R"({"traces": [{"gen": "glass", "width": 32, "height": 24}],
    "axes": {"algo": ["mlab", "alpha"], "layers": [2, 4]}})");
  fs::create_directories(p.out);
  writePlanFiles(p);
  const Plan back = readPlan(p.out);
  ASSERT_EQ(back.points.size(), p.points.size());
  for (size_t i = 0; i < p.points.size(); ++i) {
    EXPECT_EQ(back.points[i].id, p.points[i].id);
    EXPECT_EQ(back.points[i].args, p.points[i].args);
    EXPECT_EQ(back.points[i].axes, p.points[i].axes);
  }
  EXPECT_EQ(back.duplicates.size(), 1u);  // alpha at k = 4
  EXPECT_EQ(back.executable, "/usr/bin/oitsim");
  std::ifstream in(p.out / "commands.txt");
  std::string line;
  size_t n = 0;
  while (std::getline(in, line)) {
    EXPECT_EQ(line, commandLine(p, p.points[n]));
    EXPECT_EQ(line.rfind("mkdir -p " + (p.out / "points" / p.points[n].id).string() + " && /usr/bin/oitsim run ", 0),
              0u)
        << line;
    ++n;
  }
  EXPECT_EQ(n, 3u);
  // The generated trace's stamp is its generator's arguments.
  EXPECT_EQ(readTraceStamps(p.out).at("glass"), currentTraceStamp(p.traces[0]));
  EXPECT_THROW(readPlan(dir_ / "nowhere"), std::invalid_argument);
}

// `seeds` (oitsim run --seeds N, issue 23's flicker) goes to timing points
// only: `run` refuses it in functional mode, so a functional point runs
// without it and differs from its twin only in an ignored setting.
TEST_F(SweepPlanTest, SeedsGoToTimingPointsOnly) {
  const Plan p = plan(R"({"traces": [{"gen": "glass", "width": 32, "height": 24}],
    "base": {"seeds": 4}, "axes": {"mode": ["timing", "functional"], "lock.mode": ["ordered", "none"]}})");
  EXPECT_EQ(p.combinations, 4u);
  ASSERT_EQ(p.points.size(), 3u);  // functional x lock.mode: one run
  auto has = [](const Point& pt, const std::string& a, const std::string& b) {
    for (size_t i = 0; i + 1 < pt.args.size(); ++i)
      if (pt.args[i] == a && pt.args[i + 1] == b) return true;
    return false;
  };
  EXPECT_TRUE(has(p.points[0], "--seeds", "4"));
  EXPECT_TRUE(has(p.points[1], "--seeds", "4"));
  EXPECT_FALSE(has(p.points[2], "--seeds", "4"));
  EXPECT_TRUE(has(p.points[2], "--mode", "functional"));
  const std::string e = planError(R"({"traces": [{"gen": "glass"}], "base": {"seeds": 0}})");
  EXPECT_NE(e.find("s.json: base.seeds: expected a positive integer (shader-latency seeds per timing point, "
                   "`oitsim run --seeds`), got 0"),
            std::string::npos)
      << e;
}

}  // namespace
}  // namespace oit::sweep
