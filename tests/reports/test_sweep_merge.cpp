// Merging a sweep's points (reports/SweepMerge.hpp) and deciding which points a
// resumed sweep runs again (reports/SweepRunner.hpp preparePoints), on
// hand-made point folders.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "reports/SweepMerge.hpp"
#include "reports/SweepRunner.hpp"

namespace oit::sweep {
namespace {

namespace fs = std::filesystem;

class SweepFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    plan_.out = fs::path(::testing::TempDir()) / ("sweep_merge_" + std::to_string(::getpid()) + "_" +
                                                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(plan_.out);
    fs::create_directories(plan_.out / "points");
    plan_.spec = "/s/spec.json";
    plan_.executable = "/usr/bin/oitsim";
    plan_.traces.push_back({0, "t", "/traces/t.oitt", {"gen", "glass", "-o", "/traces/t.oitt"}});
    for (const char* id : {"0000-t-a", "0001-t-b", "0002-t-c", "0003-t-d"})
      plan_.points.push_back({id, "t", ojson{{"algo", std::string(id).substr(7)}}, {"run", "--algo", id}});
    writePlanFiles(plan_);
  }
  void TearDown() override { fs::remove_all(plan_.out); }
  void write(const std::string& id, const std::string& name, const std::string& text) {
    fs::create_directories(plan_.out / "points" / id);
    std::ofstream(plan_.out / "points" / id / name) << text;
  }
  Plan plan_;
};

// a: finished here; b: finished by a Slurm task (no status.json); c: failed
// (exit 1, its stderr); d: not run yet.
TEST_F(SweepFolder, MergeCountsOkFailedAndNotRunAndNamesThem) {
  write("0000-t-a", "report.json", R"({"image": {"metrics": {"rmse": 0.5}}, "timeseries": {"samples": [1, 2]}})");
  write("0000-t-a", "status.json", R"({"exit_code": 0, "wall_seconds": 1.5})");
  write("0001-t-b", "report.json", R"({"image": {"metrics": {"rmse": 0.25}}})");
  write("0002-t-c", "stderr.txt", "oitsim: error: out of memory\n");
  write("0002-t-c", "status.json", R"({"exit_code": 1, "wall_seconds": 0.1})");
  const MergeSummary s = mergeSweep(plan_.out);
  EXPECT_EQ(s.points, 4u);
  EXPECT_EQ(s.ok, 2u);
  EXPECT_EQ(s.failed, 1u);
  EXPECT_EQ(s.not_run, 1u);
  ASSERT_EQ(s.failures.size(), 1u);
  EXPECT_EQ(s.failures[0], std::make_pair(std::string("0002-t-c"), std::string("oitsim: error: out of memory")));
  EXPECT_EQ(s.not_run_ids, std::vector<std::string>{"0003-t-d"});
  const std::string text = mergeSummaryText(s);
  EXPECT_EQ(text, "sweep: 4 points, 2 ok, 1 failed, 1 not run; results " + s.csv.string() + " and " +
                      s.json.string() +
                      "\n  FAILED 0002-t-c: oitsim: error: out of memory\n  not run yet: 0003-t-d (rerun `oitsim "
                      "sweep` with the same spec and --out to run only these, or submit the Slurm array)\n");
  std::ifstream in(s.csv);
  std::stringstream csv;
  csv << in.rdbuf();
  EXPECT_EQ(csv.str(),
            "id,trace,status,error,wall_seconds,axis.algo,image.metrics.rmse\n"
            "0000-t-a,t,ok,,1.5,a,0.5\n"
            "0001-t-b,t,ok,,,b,0.25\n"
            "0002-t-c,t,failed,oitsim: error: out of memory,0.1,c,\n"
            "0003-t-d,t,not run,,,d,\n");
  // At most `list` ids of the points not run, then how many more.
  MergeSummary many;
  many.not_run_ids = {"a", "b", "c"};
  EXPECT_NE(mergeSummaryText(many, 2).find("not run yet: a, b and 1 more ("), std::string::npos);
}

// A resumed sweep runs again what has no finished result of the same command on
// the same trace; everything with --force. Run-again folders are emptied.
TEST_F(SweepFolder, ResumeKeepsOnlyFinishedPointsOfTheSameCommandAndTrace) {
  write("0000-t-a", "report.json", "{}");
  write("0000-t-a", "status.json", R"({"exit_code": 0})");
  write("0001-t-b", "report.json", "{}");  // a Slurm task's: no status.json
  write("0002-t-c", "report.json", "{}");
  write("0002-t-c", "status.json", R"({"exit_code": 1})");  // failed after writing
  const std::map<std::string, std::string> stamps = readTraceStamps(plan_.out);
  Plan now = plan_;
  PendingPoints p = preparePoints(now, &plan_, stamps, false);
  EXPECT_EQ(p.kept, 2u);
  EXPECT_EQ(p.indices, (std::vector<size_t>{2, 3}));
  EXPECT_FALSE(fs::exists(plan_.out / "points" / "0002-t-c")) << "a point to run again starts from an empty folder";
  EXPECT_TRUE(fs::exists(plan_.out / "points" / "0000-t-a" / "report.json"));

  // Another command for point a (a changed base setting): run again.
  now.points[0].args.push_back("--layers");
  p = preparePoints(now, &plan_, stamps, false);
  EXPECT_EQ(p.indices, (std::vector<size_t>{0, 2, 3}));
  // Another generator for the trace: every point of it runs again.
  write("0001-t-b", "report.json", "{}");
  now = plan_;
  now.traces[0].gen_args.push_back("--backdrop");
  p = preparePoints(now, &plan_, stamps, false);
  EXPECT_EQ(p.kept, 0u);
  // No earlier plan, or --force: all of them.
  write("0001-t-b", "report.json", "{}");
  EXPECT_EQ(preparePoints(plan_, nullptr, {}, false).indices.size(), 4u);
  write("0001-t-b", "report.json", "{}");
  EXPECT_EQ(preparePoints(plan_, &plan_, stamps, true).indices.size(), 4u);
}

}  // namespace
}  // namespace oit::sweep
