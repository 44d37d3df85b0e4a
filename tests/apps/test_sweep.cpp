// End-to-end tests of `oitsim sweep` and `oitsim report` on the real
// executable: the acceptance sweep (3 algorithms x 3 k x 2 generated traces),
// failed points, spec errors, YAML, Slurm emission, and the HTML report rendered
// by a real headless Chromium.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <cmath>
#include <sstream>

#include "CliRunner.hpp"
#include "model/Image.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;

const char* kSweepSpec = R"({
  "traces": [
    {"gen": "particles", "width": 160, "height": 90, "count": 300, "backdrop": true},
    {"gen": "hair", "width": 160, "height": 90}
  ],
  "base": {"mode": "functional", "format": "fp32"},
  "axes": {"algo": ["mlab", "hybrid", "adaptive"], "layers": [2, 4, 8]}
})";

// The acceptance sweep, run once for the tests of this file.
class Sweep : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("sweep");
    writeText(dir_->file("spec.json"), kSweepSpec);
    out_ = dir_->file("out");
    result_ = new CliResult(runOitsim("sweep " + dir_->file("spec.json") + " --out " + out_ + " --jobs 2"));
  }
  static void TearDownTestSuite() {
    delete result_;
    delete dir_;
  }
  static TempDir* dir_;
  static CliResult* result_;
  static std::string out_;
};
TempDir* Sweep::dir_ = nullptr;
CliResult* Sweep::result_ = nullptr;
std::string Sweep::out_;

TEST_F(Sweep, EveryPointRunsAndLandsInOneTable) {
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  EXPECT_NE(result_->output.find("18 points, 18 ok, 0 failed"), std::string::npos) << result_->output;
  EXPECT_NE(result_->output.find("[18/18]"), std::string::npos) << "progress lines: " << result_->output;

  const auto csv = lines(readText(out_ + "/results.csv"));
  ASSERT_EQ(csv.size(), 19u);  // header + 18 points
  const auto header = csvSplit(csv[0]);
  std::map<std::string, size_t> col;
  for (size_t i = 0; i < header.size(); ++i) col[header[i]] = i;
  for (const char* k : {"id", "trace", "status", "error", "wall_seconds", "axis.algo", "axis.layers",
                        "image.metrics.rmse", "image.metrics.ssim", "fragments.in", "config.algorithm",
                        "memory.state_bytes", "sim.wall_seconds"})
    EXPECT_TRUE(col.count(k)) << "results.csv lacks column " << k;

  const nlohmann::json res = readJson(out_ + "/results.json");
  ASSERT_EQ(res["points"].size(), 18u);
  EXPECT_EQ(res["summary"]["failed"].get<int>(), 0);
  // Traces vary slowest, then algo, then layers (spec order).
  EXPECT_EQ(res["points"][0]["id"], "0000-particles-mlab-2");
  EXPECT_EQ(res["points"][17]["id"], "0017-hair-adaptive-8");
  for (size_t i = 0; i < 18; ++i) {
    const auto& p = res["points"][i];
    const auto row = csvSplit(csv[i + 1]);
    EXPECT_EQ(row[col["id"]], p["id"].get<std::string>());
    EXPECT_EQ(row[col["status"]], "ok");
    // The table holds the point's own report, flattened.
    const nlohmann::json rep = readJson(out_ + "/points/" + p["id"].get<std::string>() + "/report.json");
    EXPECT_EQ(p["metrics"]["image.metrics.rmse"].get<double>(), rep["image"]["metrics"]["rmse"].get<double>());
    EXPECT_EQ(p["metrics"]["config.algorithm"], p["axes"]["algo"]);
    EXPECT_EQ(p["metrics"]["config.layers"].get<int>(), std::stoi(p["axes"]["layers"].get<std::string>()));
    EXPECT_EQ(p["metrics"]["config.mode"], "functional");
    EXPECT_EQ(p["metrics"]["trace.width"].get<int>(), 160);
    EXPECT_GT(p["metrics"]["image.metrics.rmse"].get<double>(), 0.0) << p["id"];
    EXPECT_EQ(p["metrics"]["fragments.passes.0.name"].is_string(), true);  // arrays of objects by index
  }
  // MLAB's state is k rows of 20 bytes (the default fp32 format: r, g, b, t, z
  // as binary32, model/FORMATS.md): 2, 4 and 8 rows per pixel.
  const auto& pts = res["points"];
  EXPECT_EQ(pts[0]["metrics"]["memory.bytes_per_pixel"].get<int>(), 2 * 20);
  EXPECT_EQ(pts[1]["metrics"]["memory.bytes_per_pixel"].get<int>(), 4 * 20);
  EXPECT_EQ(pts[2]["metrics"]["memory.bytes_per_pixel"].get<int>(), 8 * 20);
  // More MLAB rows on 300 overlapping particles: less error.
  EXPECT_GT(pts[0]["metrics"]["image.metrics.rmse"].get<double>(), pts[2]["metrics"]["image.metrics.rmse"].get<double>());
  // Both traces were generated into the sweep folder and replayed.
  EXPECT_TRUE(fs::exists(out_ + "/traces/particles.oitt"));
  EXPECT_TRUE(fs::exists(out_ + "/traces/hair.oitt"));
  EXPECT_NE(pts[0]["metrics"]["trace.fragments"], pts[9]["metrics"]["trace.fragments"]);
}

TEST_F(Sweep, TableIsDeterministicApartFromWallClock) {
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  const std::string again = dir_->file("again");
  // One job this time: scheduling must not change the table.
  CliResult r = runOitsim("sweep " + dir_->file("spec.json") + " --out " + again + " --jobs 1 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto a = lines(readText(out_ + "/results.csv"));
  const auto b = lines(readText(again + "/results.csv"));
  const size_t compared = compareSweepTables(a, b);
  EXPECT_GT(compared, 18u * 20u);
}

TEST_F(Sweep, SlurmEmitsOneTaskPerPointAndReportMergesWhatRan) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it): oitsim report cannot draw";
  const std::string out = dir_->file("slurm");
  CliResult r = runOitsim("sweep " + dir_->file("spec.json") + " --out " + out + " --emit slurm");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string script = readText(out + "/sweep.slurm");
  EXPECT_NE(script.find("#SBATCH --array=0-17"), std::string::npos) << script;
  const auto cmds = lines(readText(out + "/commands.txt"));
  ASSERT_EQ(cmds.size(), 18u);
  EXPECT_FALSE(fs::exists(out + "/points/0000-particles-mlab-2/report.json")) << "--emit must not run points";
  // What Slurm task 3 would do (the script's own line selection).
  ASSERT_EQ(std::system(("cd " + out + " && SLURM_ARRAY_TASK_ID=3 bash sweep.slurm").c_str()), 0);
  EXPECT_TRUE(fs::exists(out + "/points/0003-particles-hybrid-2/report.json"));
  r = runOitsim("report -q " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json res = readJson(out + "/results.json");
  EXPECT_EQ(res["summary"]["ok"].get<int>(), 1);
  EXPECT_EQ(res["summary"]["failed"].get<int>(), 0);  // the others have not run: not failures
  EXPECT_EQ(res["summary"]["not_run"].get<int>(), 17);
  EXPECT_EQ(res["points"][3]["status"], "ok");
  EXPECT_EQ(res["points"][0]["status"], "not run");
  EXPECT_EQ(res["points"][0]["error"], "");
}

// The page embeds every plot and thumbnail; at 160x90 the full-size images are
// the thumbnails themselves, so even the viewer needs no file. Its layout in a
// real browser: tests/apps/test_report_browser.cpp.
TEST_F(Sweep, ReportEmbedsEveryImage) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it): oitsim report cannot draw";
  ASSERT_EQ(result_->exit_code, 0) << result_->output;
  CliResult r = runOitsim("report " + out_);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string page = readText(out_ + "/report.html");
  size_t imgs = 0, embedded = 0;
  for (size_t at = page.find("<img "); at != std::string::npos; at = page.find("<img ", at + 1)) {
    ++imgs;
    const size_t end = page.find('>', at);
    embedded += page.substr(at, end - at).find("src=\"data:image/png;base64,") != std::string::npos;
  }
  // 2 traces x (3 algorithms x 3 k x image, difference, FLIP map + reference) and the plots.
  EXPECT_GE(imgs, 2u * (27u + 1u));
  EXPECT_EQ(embedded, imgs - 1) << "every <img> but the viewer's (empty until a thumbnail is clicked)";
  // The viewer's full-size sources are the embedded images too.
  EXPECT_EQ(page.find("data-image=\"points/"), std::string::npos);
  EXPECT_EQ(page.find("src=\"file:"), std::string::npos);
  EXPECT_EQ(page.find("src=\"http"), std::string::npos);
  EXPECT_NE(page.find("0017-hair-adaptive-8"), std::string::npos);
}

TEST(SweepErrors, FailedPointIsReportedAndTheSweepGoesOn) {
  TempDir d("sweep_fail");
  // Every setting is valid; the second trace is not a trace, so its points fail when they run.
  writeText(d.file("broken.oitt"), "not a trace\n");
  writeText(d.file("s.json"), R"({"traces": [{"gen": "glass", "width": 64, "height": 48}, "broken.oitt"],
    "base": {"mode": "functional"}, "axes": {"algo": ["mlab", "hybrid"]}})");
  CliResult r = runOitsim("sweep " + d.file("s.json") + " --out " + d.file("o") + " -j 2");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("4 points, 2 ok, 2 failed;"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("FAILED 0002-broken-mlab"), std::string::npos) << r.output;
  const nlohmann::json res = readJson(d.file("o") + "/results.json");
  EXPECT_EQ(res["points"][2]["status"], "failed");
  EXPECT_NE(res["points"][2]["error"].get<std::string>().find("broken.oitt"), std::string::npos)
      << res["points"][2]["error"];
  EXPECT_EQ(res["points"][1]["status"], "ok");
  EXPECT_TRUE(fs::exists(d.file("o") + "/points/0001-glass-hybrid/report.json"));
}

// A sweep run again into the same folder: a point that now fails is failed, not
// reported ok with the earlier run's report.json (each point runs in a fresh
// folder, a non-zero exit code is a failure whatever the folder holds).
TEST(SweepErrors, RerunIntoTheSameFolderNeverShowsTheOldReport) {
  TempDir d("sweep_rerun");
  writeText(d.file("broken.oitt"), "not a trace\n");
  CliResult g = runOitsim("gen glass --width 64 --height 48 -o " + d.file("good.oitt"));
  ASSERT_EQ(g.exit_code, 0) << g.output;
  writeText(d.file("a.json"), R"({"traces": [{"path": "good.oitt", "name": "t"}], "base": {"mode": "functional"},
    "axes": {"algo": ["mlab"]}})");
  writeText(d.file("b.json"), R"({"traces": [{"path": "broken.oitt", "name": "t"}], "base": {"mode": "functional"},
    "axes": {"algo": ["mlab"]}})");
  // `oitsim sweep SPEC --out o EXTRA`, always into the same folder.
  auto sweepInto = [&](const char* spec, const std::string& extra) {
    return runOitsim("sweep " + d.file(spec) + " --out " + d.file("o") + " " + extra);
  };
  CliResult a = sweepInto("a.json", "-q");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  ASSERT_TRUE(fs::exists(d.file("o") + "/points/0000-t-mlab/report.json"));
  CliResult b = sweepInto("b.json", "-q");
  EXPECT_EQ(b.exit_code, 2) << b.output;
  EXPECT_FALSE(fs::exists(d.file("o") + "/points/0000-t-mlab/report.json"));
  const nlohmann::json res = readJson(d.file("o") + "/results.json");
  EXPECT_EQ(res["points"][0]["status"], "failed");
  EXPECT_EQ(res["summary"]["failed"], 1);

  // Once the new plan is written nothing of the earlier sweep is left that is
  // not this plan's own result, even if the new one is stopped before its
  // points run (--emit slurm runs none): the old tables go (they showed the
  // earlier numbers as current after an interrupted re-sweep); a finished point
  // of the same command on the same trace is kept (a resumed sweep), every
  // other point folder of the plan is emptied, and --force empties them all.
  CliResult c = sweepInto("a.json", "-q");
  ASSERT_EQ(c.exit_code, 0) << c.output;
  ASSERT_TRUE(fs::exists(d.file("o") + "/results.json"));
  CliResult e = sweepInto("a.json", "--emit slurm");
  ASSERT_EQ(e.exit_code, 0) << e.output;
  EXPECT_NE(e.output.find("every one of the 1 points has finished: no Slurm job written"), std::string::npos)
      << e.output;
  EXPECT_FALSE(fs::exists(d.file("o") + "/results.json"));
  EXPECT_FALSE(fs::exists(d.file("o") + "/results.csv"));
  EXPECT_FALSE(fs::exists(d.file("o") + "/sweep.slurm"));
  EXPECT_TRUE(fs::exists(d.file("o") + "/points/0000-t-mlab/report.json"));
  CliResult f = sweepInto("a.json", "--emit slurm --force");
  ASSERT_EQ(f.exit_code, 0) << f.output;
  EXPECT_FALSE(fs::exists(d.file("o") + "/points/0000-t-mlab"));
  EXPECT_NE(readText(d.file("o") + "/sweep.slurm").find("#SBATCH --array=0-0"), std::string::npos);
}

TEST(SweepErrors, SpecErrorsNameTheFileAndKey) {
  TempDir d("sweep_spec");
  writeText(d.file("bad_axis.json"), R"({"traces": [{"gen": "glass"}], "axes": {"colour": ["red"]}})");
  CliResult r = runOitsim("sweep " + d.file("bad_axis.json") + " --out " + d.file("o"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("bad_axis.json: axes.colour[0]: unknown setting 'colour'"), std::string::npos) << r.output;

  writeText(d.file("no_traces.json"), R"({"axes": {"algo": ["mlab"]}})");
  r = runOitsim("sweep " + d.file("no_traces.json") + " --out " + d.file("o"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("no_traces.json: key 'traces' must be a non-empty list"), std::string::npos) << r.output;

  writeText(d.file("missing.json"), R"({"traces": ["nowhere.oitt"]})");
  r = runOitsim("sweep " + d.file("missing.json") + " --out " + d.file("o"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("missing.json: traces[0]: trace " + d.file("nowhere.oitt") + " does not exist"),
            std::string::npos)
      << r.output;

  writeText(d.file("broken.json"), R"({"traces": [)");
  r = runOitsim("sweep " + d.file("broken.json") + " --out " + d.file("o"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("broken.json: not valid JSON"), std::string::npos) << r.output;
}

// Sweeps the spec d/s.json into d/o and expects it refused (exit 1) with `message`
// in the output and nothing created.
void expectSpecRefused(const TempDir& d, const std::string& spec, const std::string& message) {
  writeText(d.file("s.json"), spec);
  CliResult r = runOitsim("sweep -q " + d.file("s.json") + " --out " + d.file("o"));
  EXPECT_EQ(r.exit_code, 1) << spec << "\n" << r.output;
  EXPECT_NE(r.output.find(message), std::string::npos) << spec << "\n" << r.output;
  EXPECT_FALSE(fs::exists(d.file("o"))) << spec << ": nothing may be created before the spec is checked";
}

TEST(SweepErrors, BadRopParameterStopsTheSweepBeforeAnyPointRuns) {
  TempDir d("sweep_rop");
  expectSpecRefused(d, R"({"traces": [{"gen": "glass", "width": 64, "height": 48}],
    "axes": {"sim.quantum_cycle": [1, 1000]}})",
                    "s.json: axes.sim.quantum_cycle[0]: sim.quantum_cycle = 1: unknown property "
                    "'sim.quantum_cycle'; did you mean 'sim.quantum_cycles'?");
}

// Every value of base and of every axis is checked before anything is created
// or run (reports/SWEEP.md); the error names the spec file, the key and the value.
TEST(SweepErrors, EveryAxisValueIsCheckedBeforeAnythingRuns) {
  TempDir d("sweep_values");
  const std::map<std::string, std::string> cases = {
      {R"("axes": {"layers": [2, "four"]})", R"(s.json: axes.layers[1]: expected a positive integer, got "four")"},
      {R"("axes": {"layers": [0]})", R"(s.json: axes.layers[0]: expected a positive integer, got 0)"},
      {R"("axes": {"algo": ["mlab", "nosuch"]})",
       R"(s.json: axes.algo[1]: expected an algorithm (abuffer, alpha, mlab, )"},
      {R"("axes": {"background": [[0, 0, 0], [2, 0, 0]]})",
       R"(s.json: axes.background[1]: expected [r, g, b], three linear values in [0,1], got [2,0,0])"},
      {R"("base": {"background": [0.5, 0.5]})",
       R"(s.json: base.background: expected [r, g, b], three linear values in [0,1], got [0.5,0.5])"},
      {R"("axes": {"format": ["fp8"]})",
       R"(s.json: axes.format[0]: expected a storage format (fp32, rgba8t8z32, fp16), got "fp8")"},
      {R"("axes": {"mode": ["fast"]})", R"(s.json: axes.mode[0]: expected functional or timing, got "fast")"},
      {R"("axes": {"preset": ["tpu"]})", R"(s.json: axes.preset[0]: expected a ROP preset (iris-pro-5200, titan-x-maxwell, navi21; aliases igpu, dgpu), got "tpu")"},
      {R"("axes": {"lock.capacity": [0, 4]})", R"(s.json: axes.lock.capacity[0]: lock.capacity = 0: )"},
      {R"("axes": {"speed": [{"label": "a", "mode": "functional"}, {"label": "b", "set": {"lock.capacity": 0}}]})",
       R"(s.json: axes.speed[1].set.lock.capacity: lock.capacity = 0: )"},
  };
  for (const auto& [spec, message] : cases) {
    const bool has_base = spec.find("\"base\"") != std::string::npos;
    expectSpecRefused(d,
                      R"({"traces": [{"gen": "glass", "width": 64, "height": 48}], )" +
                          std::string(has_base ? "" : R"("base": {"mode": "functional"}, )") + spec + "}",
                      "oitsim: error: sweep spec " + d.file(message));
  }
}

// `oitsim run` resolves the ROP configuration in both modes, so the sweep's
// up-front check does too: a bad combination in a functional sweep is refused
// (exit 1, nothing created) instead of failing every point (exit 2).
TEST(SweepErrors, FunctionalSweepChecksTheRopConfigurationToo) {
  TempDir d("sweep_func_rop");
  for (const char* mode : {"functional", "timing"})
    expectSpecRefused(d, R"({"traces": [{"gen": "glass", "width": 64, "height": 48}],
      "base": {"mode": ")" + std::string(mode) + R"(", "input.latency_min": 500}, "axes": {"algo": ["mlab"]}})",
                      "oitsim: error: sweep spec " + d.file("s.json") + ": point 0000-glass-mlab: ");
}

// The spec's top level and its keys: a list is not a spec, and a key given
// twice in one object is refused (as in config files) rather than the last
// silently winning.
TEST(SweepErrors, SpecMustBeAnObjectWithEachKeyOnce) {
  TempDir d("sweep_shape");
  expectSpecRefused(d, R"([{"traces": [{"gen": "glass"}]}])",
                    "sweep spec " + d.file("s.json") +
                        ": expected a JSON object with keys traces, base, axes at the top level, got a list");
  expectSpecRefused(d, R"({"traces": [{"gen": "glass"}], "axes": {"algo": ["mlab"]}, "axes": {"algo": ["alpha"]}})",
                    "sweep spec " + d.file("s.json") + ": key 'axes' appears twice in the same object");
  expectSpecRefused(d, R"({"traces": [{"gen": "glass"}], "base": {"mode": "functional", "mode": "timing"}})",
                    "sweep spec " + d.file("s.json") + ": key 'base.mode' appears twice in the same object");
  expectSpecRefused(d, R"({"traces": ["a.oitt", {"gen": "glass", "gen": "hair"}]})",
                    "sweep spec " + d.file("s.json") + ": key 'traces[1].gen' appears twice in the same object");
  // One ROP parameter in "set" and as a dotted key of the same object (the
  // later one won silently), in base and in an axis bundle.
  expectSpecRefused(d, R"({"traces": [{"gen": "glass"}], "base": {"set": {"cache.ways": 2}, "cache.ways": 4}})",
                    "sweep spec " + d.file("s.json") + ": base: ROP parameter cache.ways is given twice");
  expectSpecRefused(d, R"({"traces": [{"gen": "glass"}],
      "axes": {"speed": [{"label": "a", "cache.ways": 2, "set": {"cache.ways": 8}}]}})",
                    "sweep spec " + d.file("s.json") + ": axes.speed[0]: ROP parameter cache.ways is given twice");
  // A nested object in "set" names its place once (the prefix was printed twice).
  expectSpecRefused(d, R"({"traces": [{"gen": "glass"}], "base": {"set": {"cache": {"ways": 4}}}})",
                    "oitsim: error: sweep spec " + d.file("s.json") +
                        ": base.set.cache: expected a string, number or boolean, got {\"ways\":4}\n");
}

// --out that cannot be a folder: one line naming the option, as `oitsim run --out`.
TEST(SweepErrors, OutThatCannotBeAFolderIsRefusedNamingTheOption) {
  TempDir d("sweep_out");
  writeText(d.file("s.json"), R"({"traces": [{"gen": "glass", "width": 64, "height": 48}],
    "base": {"mode": "functional"}})");
  writeText(d.file("afile"), "mine\n");
  CliResult r = runOitsim("sweep -q " + d.file("s.json") + " --out " + d.file("afile"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --out " + d.file("afile") + ": exists and is not a directory\n");
  EXPECT_EQ(readText(d.file("afile")), "mine\n");
  r = runOitsim("sweep -q " + d.file("s.json") + " --out " + d.file("afile") + "/sub");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --out " + d.file("afile") + "/sub: " + d.file("afile") + " is not a directory\n");
}

// A spec's config file is found beside the spec (as its traces are), whatever
// the current directory, and the plan names it by absolute path, so a line of
// commands.txt reproduces its point from anywhere.
TEST(SweepSpec, ConfigFileIsTakenFromTheSpecFolderAndWrittenAbsolute) {
  TempDir d("sweep_cfg");
  fs::create_directories(d.path() / "specs");
  writeText(d.file("specs/cc.json"), R"({"lock": {"capacity": 32}})");
  writeText(d.file("specs/s.json"), R"({"traces": [{"gen": "glass", "width": 64, "height": 48}],
    "base": {"mode": "functional", "config": "cc.json"}, "axes": {"algo": ["mlab"]}})");
  const std::string cfg = d.file("specs/cc.json");
  // From the folder above the spec's: "cc.json" is not in the current directory.
  CliResult r = runShell("cd " + d.path().string() + " && " + oitsimPath() + " sweep specs/s.json --out o --emit slurm");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json plan = readJson(d.file("o/plan.json"));
  const auto args = plan["points"][0]["args"].get<std::vector<std::string>>();
  const auto at = std::find(args.begin(), args.end(), "--config");
  ASSERT_NE(at, args.end()) << plan.dump(1);
  EXPECT_EQ(*(at + 1), cfg);
  const std::string commands = readText(d.file("o/commands.txt"));
  EXPECT_NE(commands.find(" --config " + cfg + " "), std::string::npos) << commands;
  // The point's line, run from elsewhere, finds the file and uses it.
  ASSERT_EQ(std::system(("cd / && bash -c \"$(sed -n 1p " + d.file("o/commands.txt") + ")\"").c_str()), 0)
      << readText(d.file("o/points/0000-glass-mlab/stderr.txt"));
  const nlohmann::json rep = readJson(d.file("o/points/0000-glass-mlab/report.json"));
  EXPECT_NE(rep["oitsim"]["command"].get<std::string>().find("--config " + cfg), std::string::npos);

  // A config file that is not beside the spec is refused before anything runs.
  writeText(d.file("specs/s.json"), R"({"traces": [{"gen": "glass", "width": 64, "height": 48}],
    "base": {"mode": "functional", "config": "nowhere.json"}})");
  r = runShell("cd " + d.path().string() + " && " + oitsimPath() + " sweep -q specs/s.json --out o2");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("base.config: " + d.file("specs/nowhere.json") + ": cannot open config file"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(d.file("o2")));
}

// A timing sweep's table has the time series' period (every report field is a
// column except the samples), and a sweep into a folder that had an earlier
// --emit slurm removes its sweep.slurm (it would submit the earlier plan).
TEST(SweepSpec, TimingTableHasTheSeriesPeriodAndAStaleSlurmScriptGoes) {
  TempDir d("sweep_timing");
  writeText(d.file("s.json"), R"({"traces": [{"gen": "glass", "width": 64, "height": 48}],
    "base": {"mode": "timing", "stats.interval_cycles": 2000}, "axes": {"algo": ["mlab"]}})");
  CliResult r = runOitsim("sweep " + d.file("s.json") + " --out " + d.file("o") + " --emit slurm");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(fs::exists(d.file("o/sweep.slurm")));
  r = runOitsim("sweep -q " + d.file("s.json") + " --out " + d.file("o"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(d.file("o/sweep.slurm"))) << "a stale sweep.slurm survived the new sweep";
  const auto csv = lines(readText(d.file("o/results.csv")));
  ASSERT_EQ(csv.size(), 2u);
  const auto header = csvSplit(csv[0]), row = csvSplit(csv[1]);
  const auto col = std::find(header.begin(), header.end(), "timeseries.interval_cycles");
  ASSERT_NE(col, header.end()) << csv[0];
  const nlohmann::json rep = readJson(d.file("o/points/0000-glass-mlab/report.json"));
  EXPECT_EQ(row[size_t(col - header.begin())], rep["timeseries"]["interval_cycles"].dump());
  for (const auto& h : header) EXPECT_EQ(h.find("timeseries.samples"), std::string::npos) << h;
}

TEST(SweepErrors, UnknownSceneIsASpecErrorAndCreatesNothing) {
  TempDir d("sweep_scene");
  expectSpecRefused(d, R"({"traces": [{"gen": "nosuch"}], "axes": {"algo": ["mlab"]}})",
                    "oitsim: error: sweep spec " + d.file("s.json") +
                        ": traces[0].gen: unknown scene 'nosuch' (expected particles, ");
}

// A generator that fails when it runs: its error is shown (even with -q), nothing
// runs, and the sweep folder is left as it was (not created, or untouched).
TEST(SweepErrors, FailedGeneratorShowsItsErrorAndLeavesNoHalfMadeFolder) {
  TempDir d("sweep_gen");
  writeText(d.file("s.json"), R"({"traces": [{"gen": "glass", "width": 64, "height": 48},
    {"gen": "glass", "name": "bad", "widht": 64}], "axes": {"algo": ["mlab"]}})");
  const std::string o = d.file("o");
  CliResult r = runOitsim("sweep -q " + d.file("s.json") + " -o " + o + " -j 1");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("oitsim: error: sweep " + d.file("s.json") + ": 1 of 2 trace generator(s) failed, so "
                          "nothing ran and " + o + " was not created:\n  traces[1] bad: `oitsim gen glass --widht 64 "
                          "-o " + o + "/traces/bad.oitt` exited with code "),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("exited with code 1:\n    oitsim: error: The following arguments were not expected: 64 --widht "
                          "(see --help)\n"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(o)) << "a failed generator must not leave a half-made sweep folder";

  // An existing folder keeps what it had and gets nothing new.
  fs::create_directories(o);
  writeText(o + "/keep.txt", "mine\n");
  r = runOitsim("sweep -q " + d.file("s.json") + " -o " + o);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(o + " was left as it was:\n  traces[1] bad: "), std::string::npos) << r.output;
  std::vector<std::string> left;
  for (const auto& e : fs::recursive_directory_iterator(o)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"keep.txt"});
}

// The report's depth-complexity heatmap: transparent fragments per pixel.
TEST(InfoHeatmap, CountsEveryTransparentFragmentOnce) {
  TempDir d("heatmap");
  CliResult r = runOitsim("gen particles --width 96 --height 54 --count 200 --backdrop -o " + d.file("p.oitt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = runOitsim("info --json --heatmap " + d.file("h.pfm") + " " + d.file("p.oitt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  const model::Image h = model::readPfm(d.file("h.pfm"));
  ASSERT_EQ(h.width, 96u);
  ASSERT_EQ(h.height, 54u);
  double sum = 0, mx = 0;
  uint64_t covered = 0;
  for (const auto& p : h.pixels) {
    sum += p.r;
    mx = std::max(mx, double(p.r));
    covered += p.r > 0;
    EXPECT_EQ(p.r, p.g);
  }
  const auto& t = j["depth_complexity"]["transparent"];
  EXPECT_EQ(uint64_t(sum), t["fragments"].get<uint64_t>());
  EXPECT_EQ(uint64_t(mx), t["max"].get<uint64_t>());
  EXPECT_EQ(covered, t["covered_pixels"].get<uint64_t>());
  EXPECT_GT(sum, 0.0);
}

// A YAML spec that does not parse: one line naming the file and where the
// error is, no Python traceback; a key repeated in one mapping is refused.
TEST(SweepYaml, InvalidYamlIsOneLineNamingFileLineAndColumn) {
  if (!haveYaml()) GTEST_SKIP() << "python3-yaml absent: YAML specs unavailable";
  TempDir d("sweep_yaml_bad");
  const std::map<std::string, std::string> cases = {
      {"traces:\n  - {gen: glass\naxes: {algo: [mlab]}\n", ": not valid YAML: line 3, column 5: "},
      {"traces: [{gen: glass}]\nbase:\n  mode: functional\n  mode: timing\n",
       ": not valid YAML: line 4, column 3: key 'mode' appears twice in the same mapping"},
      {"- {gen: glass}\n", ": expected a YAML mapping with keys traces, base, axes at the top level, got a list"},
  };
  for (const auto& [yaml, message] : cases) {
    writeText(d.file("s.yaml"), yaml);
    CliResult r = runOitsim("sweep -q " + d.file("s.yaml") + " --out " + d.file("o"));
    EXPECT_EQ(r.exit_code, 1) << yaml << r.output;
    EXPECT_EQ(lines(r.output).size(), 1u) << yaml << r.output;
    EXPECT_EQ(r.output.rfind("oitsim: error: sweep spec " + d.file("s.yaml") + message, 0), 0u) << yaml << r.output;
    EXPECT_EQ(r.output.find("Traceback"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(d.file("o")));
  }
}

TEST(SweepYaml, YamlSpecWithBundlesAndRopParameters) {
  if (!haveYaml()) GTEST_SKIP() << "python3-yaml absent: YAML specs unavailable";
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it): oitsim report cannot draw";
  TempDir d("sweep_yaml");
  writeText(d.file("s.yaml"), R"(traces:
  - {gen: glass, width: 64, height: 48, name: panes}
base: {algo: mlab, layers: 4}
axes:
  speed:
    - {label: functional, mode: functional}
    - {label: cycle, mode: timing, set: {skip.idle_cycles: false, sim.quantum_cycles: 1}}
    - {label: fast, mode: timing, set: {skip.idle_cycles: true, sim.quantum_cycles: 5000}}
  cache.ways: [4]
)");
  CliResult r = runOitsim("sweep " + d.file("s.yaml") + " --out " + d.file("o") + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json res = readJson(d.file("o") + "/results.json");
  ASSERT_EQ(res["points"].size(), 3u);
  EXPECT_EQ(res["points"][0]["id"], "0000-panes-functional-4");
  EXPECT_EQ(res["points"][0]["metrics"]["config.mode"], "functional");
  const auto& t = res["points"][1]["metrics"];
  EXPECT_EQ(t["config.mode"], "timing");
  EXPECT_EQ(t["config.rop.sim.quantum_cycles"].get<int>(), 1);
  EXPECT_EQ(t["config.rop.skip.idle_cycles"].get<bool>(), false);
  EXPECT_EQ(t["config.rop.cache.ways"].get<int>(), 4);
  EXPECT_EQ(t["timing.skipped_idle_cycles"].get<int>(), 0);
  EXPECT_GT(t["timing.cycles"].get<int>(), 0);

  // The report's speed-mode figures: the fast mode against the cycle-by-cycle one.
  r = runOitsim("report -q " + d.file("o"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json sp = readJson(d.file("o") + "/speed.json");
  const auto& f = res["points"][2]["metrics"];
  ASSERT_EQ(sp["rows"].size(), 3u);
  std::map<std::string, nlohmann::json> by_mode;
  for (const auto& row : sp["rows"]) by_mode[row["mode"].get<std::string>()] = row;
  ASSERT_TRUE(by_mode.count("functional") && by_mode.count("timing q=1 skip=off") && by_mode.count("timing q=5000 skip=on"))
      << sp.dump(1);
  EXPECT_EQ(by_mode["timing q=1 skip=off"]["cycle_err_pct"].get<double>(), 0.0);
  const double c0 = t["timing.cycles"].get<double>(), c1 = f["timing.cycles"].get<double>();
  // Signed (reports/make_report.py: 100 (c1 - c0) / c0); the mode's maximum is its magnitude.
  EXPECT_NEAR(by_mode["timing q=5000 skip=on"]["cycle_err_pct"].get<double>(), 100.0 * (c1 - c0) / c0, 1e-9);
  EXPECT_NEAR(sp["modes"]["timing q=5000 skip=on"]["max_cycle_err_pct"].get<double>(), 100.0 * std::abs(c1 - c0) / c0, 1e-9);
  EXPECT_NEAR(by_mode["timing q=5000 skip=on"]["speedup"].get<double>(),
              t["sim.wall_seconds"].get<double>() / f["sim.wall_seconds"].get<double>(), 1e-9);
  EXPECT_FALSE(by_mode["functional"].contains("cycle_err_pct"));
  EXPECT_EQ(sp["modes"].size(), 1u);  // only the fast mode is judged
  const auto& v = sp["modes"]["timing q=5000 skip=on"];
  EXPECT_EQ(v["goal_met"].get<bool>(),
            v["max_cycle_err_pct"].get<double>() <= 1.0 && v["min_speedup"].get<double>() >= 10.0);
  const std::string page = readText(d.file("o") + "/report.html");
  EXPECT_NE(page.find("Simulator speed modes"), std::string::npos);
  EXPECT_NE(page.find("<h3>Where the time goes</h3>"), std::string::npos);
}

}  // namespace
}  // namespace oit::test
