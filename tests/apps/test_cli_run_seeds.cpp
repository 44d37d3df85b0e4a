// `oitsim run` and the interlock's order: lock.mode and --seeds end to end.
// Bad settings are one line, exit 1, nothing written; on a generated
// particles scene (640x360, MLAB k = 2 rgba8t8z32, the paper's rows) the
// image of an unordered or unlocked ROP flickers across shader-latency seeds
// and an ordered one's does not.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;

// The audit's 64x48 glass trace, shared by the tests of this file.
struct CliRunSeedsTrace {
  static constexpr const char* kFolder = "cli_run_seeds";
  static constexpr const char* kFile = "glass.oitt";
  static constexpr const char* kGen = "gen glass --width 64 --height 48";
};
class CliRunSeeds : public GeneratedTraceSuite<CliRunSeedsTrace> {};

TEST_F(CliRunSeeds, BadOrderingSettingsAreOneLineAndWriteNothing) {
  const std::string out = dir_->file("bad");
  const std::pair<std::string, std::string> cases[] = {
      {"--set lock.mode=sometimes",
       "--set 'lock.mode=sometimes': lock.mode: 'sometimes' is not a known value; expected one of ordered | "
       "unordered | none"},
      {"--set lock.ordered=false",
       "--set 'lock.ordered=false': 'lock.ordered' was replaced by lock.mode (ordered | unordered | none): "
       "lock.ordered=true is lock.mode=ordered; lock.ordered=false is lock.mode=unordered, whose image now follows "
       "the order the fragments enter the lock (oit_rop/DESIGN.md)"},
      {"--seeds 0", "--seeds 0: expected the number of shader-latency seeds to run, at least 1"},
      {"--seeds 4 --mode functional",
       "--seeds 4: flicker across shader-latency seeds needs the timing model; drop --mode functional (the "
       "default is timing)"},
      {"--seeds 2 --reference none",
       "--seeds 2: the flicker measures each seed's image against the reference; --reference none has none (give "
       "--reference abuffer or FILE.pfm)"},
      {"--mode functional --set lock.mode=unordered",
       "lock.mode=unordered needs the timing model (its image follows the order the timing run lets fragments "
       "into the lock); --mode functional inserts in submission order, which is lock.mode=ordered"},
      {"--set sim.engine=approximate --set lock.mode=none",
       "invalid configuration (preset iris-pro-5200): lock.mode=none is not modelled by sim.engine=approximate (it visits "
       "fragments in submission order, so it cannot apply inserts in lock-entry order or race them); use "
       "sim.engine=cycle or lock.mode=ordered"},
  };
  for (const auto& [options, message] : cases) {
    SCOPED_TRACE(options);
    CliResult r = runOitsim("run -q -t " + trace_ + " -o " + out + " " + options);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_EQ(r.output, "oitsim: error: " + message + "\n");
    EXPECT_FALSE(fs::exists(out));
  }
  // The parent keeps every seed's image: more seeds than memory holds are refused up front.
  CliResult r = runOitsim("run -q -t " + trace_ + " -o " + out + " --seeds 4000000000");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  // 4e9 x (12 B image + 3 B sRGB8 codes) x 3072 pixels: about 150,000 GiB.
  EXPECT_EQ(r.output.rfind("oitsim: error: " + trace_ + ": a 64 x 48 frame with mlab and 4000000000 seeds' images "
                           "needs about ", 0),
            0u)
      << r.output;
  EXPECT_NE(r.output.find("GiB at its peak (outputs), more than the memory budget of"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

// The report says which order made the image; --seeds writes flicker.png and
// image.flicker beside the usual files, seed 0's run being the main report.
TEST_F(CliRunSeeds, SeedsWriteFlickerBesideTheMainRun) {
  const std::string one = dir_->file("one"), three = dir_->file("three");
  ASSERT_EQ(runOitsim("run -q -t " + trace_ + " -o " + one + " --set lock.mode=unordered --set input.seed=5").exit_code, 0);
  CliResult r = runOitsim("run -q -t " + trace_ + " -o " + three + " --seeds 3 --set lock.mode=unordered --set input.seed=5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"image.png", "image.pfm", "reference.pfm", "diff.png", "flicker.png", "report.json"})
    EXPECT_TRUE(fs::exists(three + "/" + f)) << f;
  EXPECT_FALSE(fs::exists(one + "/flicker.png"));
  const auto a = readJson(one + "/report.json"), b = readJson(three + "/report.json");
  EXPECT_EQ(a["image"]["order"], "lock_entry");
  EXPECT_FALSE(a["image"].contains("flicker"));
  EXPECT_EQ(readText(one + "/image.pfm"), readText(three + "/image.pfm"));  // seed 0 = input.seed 5
  EXPECT_EQ(a["timing"], b["timing"]);
  EXPECT_EQ(a["lock"], b["lock"]);
  const auto& f = b["image"]["flicker"];
  EXPECT_EQ(f["seeds"], 3);
  ASSERT_EQ(f["per_seed"].size(), 3u);
  for (unsigned i = 0; i < 3; ++i) EXPECT_EQ(f["per_seed"][i]["input_seed"], 5 + i);
  EXPECT_EQ(f["per_seed"][0]["cycles"], b["timing"]["cycles"]);
  EXPECT_EQ(f["per_seed"][0]["rmse"], b["image"]["metrics"]["rmse"]);
  EXPECT_EQ(f["png"], "flicker.png");
  EXPECT_EQ(f["png_scale"], 8.0);
  EXPECT_EQ(b["image"]["files"]["flicker_png"], "flicker.png");

  // Functional and ordered runs keep the submission order.
  const std::string fn = dir_->file("fn");
  ASSERT_EQ(runOitsim("run -q --mode functional -t " + trace_ + " -o " + fn).exit_code, 0);
  EXPECT_EQ(readJson(fn + "/report.json")["image"]["order"], "submission");
  ASSERT_EQ(runOitsim("run -q -t " + trace_ + " -o " + fn + " --set lock.mode=none").exit_code, 0);
  EXPECT_EQ(readJson(fn + "/report.json")["image"]["order"], "race");
}

// lock.mode is a sweep axis like any ROP parameter (the generic dotted-key
// axes): one point per mode, each with its image.order and lost updates.
TEST_F(CliRunSeeds, LockModeIsASweepAxis) {
  const std::string spec = dir_->file("modes.json"), out = dir_->file("modes_sweep");
  writeText(spec, R"({"traces": [")" + trace_ + R"("], "base": {"algo": "alpha", "format": "rgba8t8z32"},
                      "axes": {"lock.mode": ["ordered", "unordered", "none"]}})");
  CliResult r = runOitsim("sweep " + spec + " --out " + out + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto res = readJson(out + "/results.json");
  ASSERT_EQ(res["points"].size(), 3u);
  const char* order[] = {"submission", "lock_entry", "race"};
  const char* mode[] = {"ordered", "unordered", "none"};
  for (unsigned i = 0; i < 3; ++i) {
    const auto& p = res["points"][i];
    EXPECT_EQ(p["status"], "ok");
    EXPECT_EQ(p["metrics"]["lock.mode"], mode[i]);
    EXPECT_EQ(p["metrics"]["image.order"], order[i]);
    EXPECT_TRUE(p["metrics"].contains("lock.lost_updates"));
  }
}

// The issue's acceptance scene: particles at 640x360, MLAB k = 2 in the
// paper's 8-byte rows, igpu, 8 seeds. Ordered: every seed's image the same
// (no flicker); unordered and none: some pixels differ between seeds, and
// the racing read-modify-writes of none lose updates and are further from the
// A-buffer than unordered. (fp32 rows at the igpu's fp32 blend rate show no
// unordered flicker on this scene: reports/repro/ordering explains why.)
TEST_F(CliRunSeeds, ParticlesFlickerUnorderedAndUnlockedButNotOrdered) {
  const std::string trace = dir_->file("particles.oitt");
  ASSERT_EQ(runOitsim("gen particles --width 640 --height 360 -q -o " + trace).exit_code, 0);
  nlohmann::json flicker[3];
  const char* modes[] = {"ordered", "unordered", "none"};
  for (int m = 0; m < 3; ++m) {
    SCOPED_TRACE(modes[m]);
    const std::string out = dir_->file(std::string("particles_") + modes[m]);
    CliResult r = runOitsim("run -q -t " + trace + " -o " + out + " -a mlab -k 2 --format rgba8t8z32 --seeds 8 --set lock.mode=" +
                            modes[m]);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    flicker[m] = readJson(out + "/report.json")["image"]["flicker"];
    ASSERT_EQ(flicker[m]["seeds"], 8);
  }
  const auto& o = flicker[0];
  EXPECT_EQ(o["std_max"].get<double>(), 0.0);
  EXPECT_EQ(o["std_mean"].get<double>(), 0.0);
  EXPECT_EQ(o["differing_pixels"].get<uint64_t>(), 0u);
  for (const auto& s : o["per_seed"]) EXPECT_EQ(s["rmse"], o["per_seed"][0]["rmse"]);
  for (int m = 1; m < 3; ++m) {
    SCOPED_TRACE(modes[m]);
    EXPECT_GT(flicker[m]["std_mean"].get<double>(), 0.0);
    EXPECT_GT(flicker[m]["differing_pixels"].get<uint64_t>(), 0u);
  }
  for (const auto& s : flicker[2]["per_seed"]) EXPECT_GT(s["lost_updates"].get<uint64_t>(), 0u);
  EXPECT_GT(flicker[2]["rmse_mean"].get<double>(), flicker[1]["rmse_mean"].get<double>());
  EXPECT_GT(flicker[2]["differing_pixels"].get<uint64_t>(), flicker[1]["differing_pixels"].get<uint64_t>());
}

}  // namespace
}  // namespace oit::test
