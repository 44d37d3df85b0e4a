// `oitsim sweep` at scale, on the real executable: a resumed sweep runs only
// what has not finished, --emit slurm chunks points into array tasks with the
// site's options, bad Slurm options and axes no point uses are refused before
// anything is created, and points that differ only in ignored settings run once.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;

const char* kResumeSpec = R"({"traces": [{"gen": "glass", "width": 48, "height": 32}],
  "base": {"mode": "functional"}, "axes": {"algo": ["mlab", "hybrid", "adaptive"]}})";

TEST(SweepScale, ResumedSweepRunsOnlyWhatHasNotFinished) {
  TempDir d("sweep_resume");
  writeText(d.file("s.json"), kResumeSpec);
  const std::string o = d.file("o");
  CliResult r = runOitsim("sweep " + d.file("s.json") + " --out " + o + " -j 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string table = readText(o + "/results.csv");
  const std::string kept_report = readText(o + "/points/0000-glass-mlab/report.json");
  // An interrupted point: its folder holds only a stderr.txt.
  fs::remove_all(o + "/points/0001-glass-hybrid");
  fs::create_directories(o + "/points/0001-glass-hybrid");
  writeText(o + "/points/0001-glass-hybrid/stderr.txt", "");
  r = runOitsim("sweep " + d.file("s.json") + " --out " + o + " -j 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("trace glass: " + o + "/traces/glass.oitt is up to date"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("sweep: 2 of 3 points finished earlier with the same command and trace: kept"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("3 points (1 traces), 1 to run"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("[1/1] ok     0001-glass-hybrid"), std::string::npos) << r.output;
  EXPECT_EQ(readText(o + "/points/0000-glass-mlab/report.json"), kept_report) << "a finished point is not rerun";
  // The resumed table equals the first one cell by cell, but for wall clocks and paths.
  EXPECT_GT(compareSweepTables(lines(table), lines(readText(o + "/results.csv"))), 3u * 40u);
  // --force runs them all again.
  r = runOitsim("sweep " + d.file("s.json") + " --out " + o + " -j 2 --force");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("trace glass: generated"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("[3/3]"), std::string::npos) << r.output;
}

// Three points at two per task: task 0 runs points 0 and 1, task 1 point 2.
TEST(SweepScale, SlurmTasksRunChunksOfPointsWithTheSiteOptions) {
  TempDir d("sweep_chunks");
  writeText(d.file("s.json"), kResumeSpec);
  const std::string o = d.file("o");
  CliResult r = runOitsim("sweep " + d.file("s.json") + " --out " + o +
                          " --emit slurm --points-per-task 2 --time 0:30:00 --mem 2G --partition short "
                          "--sbatch=--account=arch");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("(2 tasks of up to 2 points, 3 points in all)"), std::string::npos) << r.output;
  const std::string script = readText(o + "/sweep.slurm");
  for (const char* line : {"#SBATCH --array=0-1\n", "#SBATCH --time=0:30:00\n", "#SBATCH --mem=2G\n",
                           "#SBATCH --partition=short\n", "#SBATCH --account=arch\n"})
    EXPECT_NE(script.find(line), std::string::npos) << line << script;
  EXPECT_EQ(readText(o + "/slurm-tasks.txt"), "0 1\n2\n");
  ASSERT_EQ(std::system(("cd " + o + " && SLURM_ARRAY_TASK_ID=1 bash sweep.slurm").c_str()), 0);
  EXPECT_FALSE(fs::exists(o + "/points/0000-glass-mlab/report.json"));
  EXPECT_TRUE(fs::exists(o + "/points/0002-glass-adaptive/report.json"));
  ASSERT_EQ(std::system(("cd " + o + " && SLURM_ARRAY_TASK_ID=0 bash sweep.slurm").c_str()), 0);
  EXPECT_TRUE(fs::exists(o + "/points/0000-glass-mlab/report.json"));
  EXPECT_TRUE(fs::exists(o + "/points/0001-glass-hybrid/report.json"));
  // Emitted again: nothing left to run, no job.
  r = runOitsim("sweep " + d.file("s.json") + " --out " + o + " --emit slurm");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("every one of the 3 points has finished: no Slurm job written"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(o + "/sweep.slurm"));
}

// A task whose first point fails still runs its second, and exits non-zero.
TEST(SweepScale, AFailedPointDoesNotStopItsTask) {
  TempDir d("sweep_task_fail");
  writeText(d.file("broken.oitt"), "not a trace\n");
  writeText(d.file("s.json"), R"({"traces": ["broken.oitt", {"gen": "glass", "width": 32, "height": 24}],
    "base": {"mode": "functional"}, "axes": {"algo": ["mlab"]}})");
  const std::string o = d.file("o");
  ASSERT_EQ(runOitsim("sweep -q " + d.file("s.json") + " --out " + o + " --emit slurm --points-per-task 2").exit_code,
            0);
  EXPECT_NE(std::system(("cd " + o + " && SLURM_ARRAY_TASK_ID=0 bash sweep.slurm").c_str()), 0);
  EXPECT_TRUE(fs::exists(o + "/points/0000-broken-mlab/stderr.txt"));
  EXPECT_TRUE(fs::exists(o + "/points/0001-glass-mlab/report.json"));
  const CliResult r = runOitsim("report " + o);
  EXPECT_NE(r.output.find("sweep: 2 points, 1 ok, 1 failed;"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("FAILED 0000-broken-mlab: "), std::string::npos) << r.output;
}

// Each refused before anything is created: one line naming the option or key.
TEST(SweepScale, BadSlurmOptionsAndUnusedAxesAreRefusedBeforeAnythingIsCreated) {
  TempDir d("sweep_bad_scale");
  writeText(d.file("s.json"), kResumeSpec);
  writeText(d.file("unused.json"), R"({"traces": [{"gen": "glass"}], "axes": {"algo": ["abuffer"], "layers": [2, 4]}})");
  const std::string spec = d.file("s.json"), o = d.file("o");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"sweep " + spec + " --out " + o + " --emit slurm --points-per-task 0",
       "oitsim: error: --points-per-task 0: expected a positive number of points per Slurm array task\n"},
      {"sweep " + spec + " --out " + o + " --emit slurm --time 2h",
       "oitsim: error: --time 2h: not a Slurm time limit (expected minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM or "
       "D-HH:MM:SS, e.g. 30 or 2:00:00)\n"},
      {"sweep " + spec + " --out " + o + " --emit slurm --mem 2GB",
       "oitsim: error: --mem 2GB: not a Slurm memory size (expected a whole number with an optional K, M, G or T "
       "suffix, e.g. 2G)\n"},
      {"sweep " + spec + " --out " + o + " --time 30",
       "oitsim: error: --time is an option of --emit slurm (add it, or drop --time)\n"},
      {"sweep " + d.file("unused.json") + " --out " + o,
       "oitsim: error: sweep spec " + d.file("unused.json") +
           ": axes.layers: no point uses this axis (abuffer ignores layers); remove it\n"},
  };
  for (const auto& [cmd, message] : cases) {
    const CliResult r = runOitsim(cmd);
    EXPECT_EQ(r.exit_code, 1) << cmd << "\n" << r.output;
    EXPECT_EQ(r.output, message) << cmd;
    EXPECT_FALSE(fs::exists(o)) << cmd << ": nothing may be created";
  }
}

// 2 algorithms x 3 k: wboit ignores k, so 4 points run, and a line says so.
TEST(SweepScale, PointsDifferingOnlyInIgnoredSettingsRunOnce) {
  TempDir d("sweep_dedup");
  writeText(d.file("s.json"), R"({"traces": [{"gen": "glass", "width": 32, "height": 24}],
    "base": {"mode": "functional"}, "axes": {"algo": ["mlab", "wboit"], "layers": [1, 2, 4]}})");
  const CliResult r = runOitsim("sweep " + d.file("s.json") + " --out " + d.file("o"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("sweep: 2 of 6 combinations differ only in settings their algorithm or mode ignores and "
                          "are planned once (layers: wboit): 4 points"),
            std::string::npos)
      << r.output;
  const nlohmann::json res = readJson(d.file("o/results.json"));
  ASSERT_EQ(res["points"].size(), 4u);
  EXPECT_EQ(res["points"][3]["id"], "0003-glass-wboit-1");
  ASSERT_EQ(res["duplicates"].size(), 2u);
  EXPECT_EQ(res["duplicates"][1]["labels"], "glass-wboit-4");
  EXPECT_EQ(res["duplicates"][1]["same_as"], "0003-glass-wboit-1");
}

}  // namespace
}  // namespace oit::test
