// `oitsim report` on the real executable: a bad --out is one clear error before
// anything is written, a failure of reports/make_report.py is one line and its
// exit code (not a traceback or a raw wait status), and points that have not
// run (after --emit slurm) are counted as "not run", apart from failures.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <map>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;

// One small sweep (two functional points on a 64x48 trace), run once.
class Report : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("report");
    writeText(dir_->file("spec.json"), R"({"traces": [{"gen": "glass", "width": 64, "height": 48}],
      "base": {"mode": "functional"}, "axes": {"algo": ["mlab", "hybrid"]}})");
    result_ = new CliResult(runOitsim("sweep -q " + dir_->file("spec.json") + " --out " + dir_->file("sw") + " -j 2"));
  }
  static void TearDownTestSuite() {
    delete result_;
    delete dir_;
  }
  // A fresh copy of the sweep folder, so tests that break it stay apart.
  static std::string copyOfSweep(const std::string& name) {
    const std::string to = dir_->file(name);
    fs::remove_all(to);
    fs::copy(dir_->file("sw"), to, fs::copy_options::recursive);
    return to;
  }
  static TempDir* dir_;
  static CliResult* result_;
};
TempDir* Report::dir_ = nullptr;
CliResult* Report::result_ = nullptr;

TEST_F(Report, UnwritableOutIsOneErrorNamingTheOptionBeforeAnythingRuns) {
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  const std::string sw = copyOfSweep("unwritable");
  fs::remove(sw + "/results.json");
  CliResult r = runOitsim("report " + sw + " -o /proc/x/r.html");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: report: --out /proc/x/r.html: folder /proc/x does not exist\n");
  EXPECT_FALSE(fs::exists(sw + "/results.json")) << "a bad --out must stop the report before it writes anything";

  // An existing folder is not an HTML file.
  r = runOitsim("report " + sw + " --out " + dir_->file("unwritable"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: report: --out " + dir_->file("unwritable") +
                          ": is a folder (expected an HTML file path)\n");
}

TEST_F(Report, GeneratorIoErrorIsOneLineAndTheRealExitCode) {
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
  const std::string sw = copyOfSweep("ioerror");
  fs::create_directories(sw + "/speed.json");  // the script cannot write its speed.json
  CliResult r = runOitsim("report " + sw);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output.find("Traceback"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("exit status"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("make_report.py: error: cannot read or write " + sw + "/speed.json: Is a directory\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("oitsim: error: report: " + std::string(OITSIM_SOURCE_DIR) +
                          "/reports/make_report.py failed (exit code 1); " + sw + "/report.html was not written\n"),
            std::string::npos)
      << r.output;
  // The merge's summary line and the script's progress lines ("report: ..."),
  // then the script's error and oitsim's: one line each.
  EXPECT_EQ(r.output.rfind("sweep: 2 points, 2 ok, 0 failed; results ", 0), 0u) << r.output;
  size_t errors = 0;
  for (const auto& l : lines(r.output)) errors += l.rfind("sweep: ", 0) != 0 && l.rfind("report: ", 0) != 0;
  EXPECT_EQ(errors, 2u) << r.output;
  EXPECT_FALSE(fs::exists(sw + "/report.html"));
  EXPECT_FALSE(fs::exists(sw + "/report.html.tmp"));
}

TEST_F(Report, PointsNotRunAreCountedApartFromFailures) {
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  const std::string out = dir_->file("slurm");
  CliResult r = runOitsim("sweep " + dir_->file("spec.json") + " --out " + out + " --emit slurm");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
  r = runOitsim("report " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 points: 0 ok, 0 failed, 2 not run"), std::string::npos) << r.output;
  nlohmann::json res = readJson(out + "/results.json");
  EXPECT_EQ(res["summary"], nlohmann::json({{"points", 2}, {"ok", 0}, {"failed", 0}, {"not_run", 2}}));
  for (const auto& p : res["points"]) {
    EXPECT_EQ(p["status"], "not run") << p["id"];
    EXPECT_EQ(p["error"], "") << p["id"];
  }
  auto csv = lines(readText(out + "/results.csv"));
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csvSplit(csv[1])[2], "not run");
  std::string page = readText(out + "/report.html");
  EXPECT_NE(page.find("<span class='notrun'>2 not run</span>"), std::string::npos);
  EXPECT_EQ(page.find("<h2>Failed points</h2>"), std::string::npos);

  // Point 0 runs (as its Slurm task would); point 1 fails: its stderr, no report.
  const auto cmds = lines(readText(out + "/commands.txt"));
  ASSERT_EQ(cmds.size(), 2u);
  writeText(dir_->file("task0.sh"), cmds[0] + "\n");
  ASSERT_EQ(std::system(("bash " + dir_->file("task0.sh")).c_str()), 0) << cmds[0];
  const std::string p1 = res["points"][1]["id"].get<std::string>();
  fs::create_directories(out + "/points/" + p1);
  writeText(out + "/points/" + p1 + "/stderr.txt", "oitsim: error: out of memory\n");
  r = runOitsim("report -q " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  res = readJson(out + "/results.json");
  EXPECT_EQ(res["summary"], nlohmann::json({{"points", 2}, {"ok", 1}, {"failed", 1}, {"not_run", 0}}));
  EXPECT_EQ(res["points"][0]["status"], "ok");
  EXPECT_EQ(res["points"][1]["status"], "failed");
  EXPECT_EQ(res["points"][1]["error"], "oitsim: error: out of memory");
  page = readText(out + "/report.html");
  EXPECT_NE(page.find("<h2>Failed points</h2>"), std::string::npos);
  EXPECT_EQ(page.find("not run"), std::string::npos);
  // No speed-mode group (functional points only): speed.json is still an object
  // (it held just `null`), with no rows, and the page has no speed section.
  const nlohmann::json sp = readJson(out + "/speed.json");
  EXPECT_TRUE(sp["rows"].empty()) << sp.dump();
  EXPECT_TRUE(sp["modes"].empty()) << sp.dump();
  EXPECT_FALSE(sp["goal_met"].get<bool>());
  EXPECT_NE(sp["note"].get<std::string>().find("no speed-mode group"), std::string::npos);
  EXPECT_EQ(page.find("Simulator speed modes"), std::string::npos);

  // A point that started but never finished (interrupted: only an empty
  // stderr.txt) is a failure with a message; the report crashed on it.
  fs::remove_all(out + "/points/" + p1);
  fs::create_directories(out + "/points/" + p1);
  writeText(out + "/points/" + p1 + "/stderr.txt", "");
  r = runOitsim("report -q " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  res = readJson(out + "/results.json");
  EXPECT_EQ(res["points"][1]["status"], "failed");
  EXPECT_EQ(res["points"][1]["error"],
            "no status.json and no report.json: the point started but did not finish (interrupted?)");
}

// Speed modes are compared only with the cycle-by-cycle run of the same
// hardware: a cache.ways axis makes two groups, each against its own reference
// (audit: both ways fell in one group and the ways=8 points were measured
// against ways=2, a 15.9 % "error"). Errors are signed.
TEST(ReportSpeedModes, GroupsByEveryRopParameterAndErrorsAreSigned) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
  TempDir dir("report-speed");
  writeText(dir.file("spec.json"), R"({"traces": [{"gen": "glass", "width": 64, "height": 48}],
    "base": {"mode": "timing", "algo": "mlab", "layers": 4},
    "axes": {"cache.ways": [2, 8], "speed": [
      {"label": "fast", "set": {"skip.idle_cycles": true, "sim.quantum_cycles": 200}},
      {"label": "cycle", "set": {"skip.idle_cycles": false, "sim.quantum_cycles": 1}}]}})");
  CliResult r = runOitsim("sweep -q " + dir.file("spec.json") + " --out " + dir.file("sw") + " -j 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = runOitsim("report -q " + dir.file("sw"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json res = readJson(dir.file("sw/results.json"));
  std::map<std::string, uint64_t> cycles;  // "ways/label" -> timing.cycles
  for (const auto& p : res["points"]) {
    const auto& m = p["metrics"];
    cycles[std::to_string(m["config.rop.cache.ways"].get<int>()) + "/" +
           (m["config.rop.sim.quantum_cycles"].get<int>() == 1 ? "cycle" : "fast")] = m["timing.cycles"].get<uint64_t>();
  }
  ASSERT_EQ(cycles.size(), 4u);
  const nlohmann::json sp = readJson(dir.file("sw/speed.json"));
  ASSERT_EQ(sp["rows"].size(), 4u) << sp.dump();
  for (const auto& row : sp["rows"]) {
    const std::string cfg = row["config"].get<std::string>();
    const std::string ways = cfg.find("cache.ways=2") != std::string::npos ? "2"
                             : cfg.find("cache.ways=8") != std::string::npos ? "8" : "?";
    ASSERT_NE(ways, "?") << cfg;  // the label names the setting that tells the groups apart
    const bool ref = row["mode"] == "timing q=1 skip=off";
    const double want = ref ? 0.0
                            : 100.0 * (double(cycles[ways + "/fast"]) - double(cycles[ways + "/cycle"])) /
                                  double(cycles[ways + "/cycle"]);
    EXPECT_NEAR(row["cycle_err_pct"].get<double>(), want, 1e-9) << cfg << " " << row["mode"];
  }
  EXPECT_EQ(sp["modes"]["timing q=200 skip=on"]["groups"].get<int>(), 2);
  // A numeric sweep axis gets its own line plot (cache.ways: 2, 8); the speed
  // axis's labels are not numbers.
  const std::string page = readText(dir.file("sw/report.html"));
  EXPECT_NE(page.find("alt=\"glass: against cache.ways\""), std::string::npos);
  EXPECT_EQ(page.find("against speed"), std::string::npos);
}

// The signed error of a speed mode, on a hand-made results set (a real sweep's
// fast mode may land on either side of, or exactly on, its reference). Two
// groups (cache.ways 2 and 8), each with its cycle-by-cycle reference of 1000
// cycles: the fast mode is 3 % short in one, 2 % long in the other. Rows keep
// the sign (reports/make_report.py: 100 (c1 - c0) / c0); the mode's
// max_cycle_err_pct is the largest absolute value, 3.
TEST(ReportSpeedModes, RowErrorsKeepTheirSignAndTheModeTakesTheLargestMagnitude) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
  TempDir dir("report-speed-signed");
  nlohmann::json points = nlohmann::json::array();
  int id = 0;
  for (const auto& [ways, fast_cycles] : {std::pair{2, 970}, std::pair{8, 1020}})
    for (const bool fast : {false, true}) {
      nlohmann::json m = {{"config.mode", "timing"},
                          {"config.algorithm", "mlab"},
                          {"config.layers", 4},
                          {"config.format", "rgba8t8z32"},
                          {"config.rop.cache.ways", ways},
                          {"config.rop.sim.quantum_cycles", fast ? 200 : 1},
                          {"config.rop.skip.idle_cycles", fast},
                          {"sim.wall_seconds", fast ? 0.1 : 2.0},
                          {"timing.cycles", fast ? fast_cycles : 1000}};
      points.push_back({{"id", std::to_string(id++)}, {"trace", "t"}, {"metrics", m}});
    }
  writeText(dir.file("points.json"), points.dump());
  const CliResult r = runShell("/usr/bin/python3 -c 'import json, sys; sys.path.insert(0, sys.argv[1]); "
                               "import make_report; json.dump(make_report.speed_modes(json.load(open(sys.argv[2]))), "
                               "open(sys.argv[3], \"w\"))' " +
                               std::string(OITSIM_SOURCE_DIR) + "/reports " + dir.file("points.json") + " " +
                               dir.file("speed.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json sp = readJson(dir.file("speed.json"));
  ASSERT_EQ(sp["rows"].size(), 4u) << sp.dump();
  std::map<std::string, double> err;  // "ways/mode" -> cycle_err_pct
  for (const auto& row : sp["rows"])
    err[row["config"].get<std::string>() + "/" + row["mode"].get<std::string>()] = row["cycle_err_pct"].get<double>();
  EXPECT_DOUBLE_EQ(err.at("mlab k=4 rgba8t8z32 cache.ways=2/timing q=200 skip=on"), -3.0);
  EXPECT_DOUBLE_EQ(err.at("mlab k=4 rgba8t8z32 cache.ways=8/timing q=200 skip=on"), 2.0);
  EXPECT_DOUBLE_EQ(err.at("mlab k=4 rgba8t8z32 cache.ways=2/timing q=1 skip=off"), 0.0);
  EXPECT_DOUBLE_EQ(err.at("mlab k=4 rgba8t8z32 cache.ways=8/timing q=1 skip=off"), 0.0);
  const auto& mode = sp["modes"]["timing q=200 skip=on"];
  EXPECT_EQ(mode["groups"].get<int>(), 2);
  EXPECT_DOUBLE_EQ(mode["max_cycle_err_pct"].get<double>(), 3.0);
  EXPECT_DOUBLE_EQ(mode["min_speedup"].get<double>(), 20.0);
  EXPECT_FALSE(mode["goal_met"].get<bool>());  // 3 % > 1 %
}

}  // namespace
}  // namespace oit::test
