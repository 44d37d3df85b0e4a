// `oitsim run` writes LDR-FLIP beside the other error metrics: flip.png (map
// and scale) and image.metrics.flip, at --ppd; its summary names only the
// settings the algorithm uses.
#include <gtest/gtest.h>
#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "CliRunner.hpp"
#include "model/Flip.hpp"
#include "model/Image.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;

// Each test's own folder, with a small hair trace (hair: thin overlapping
// strands, where the approximate algorithms differ from the reference).
class CliRunFlip : public ::testing::Test {
 protected:
  void SetUp() override {
    CliResult r = runOitsim("gen hair -q --width 96 --height 54 -o " + trace_);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  TempDir dir_{std::string("cli_run_flip_") + ::testing::UnitTest::GetInstance()->current_test_info()->name()};
  const std::string trace_ = dir_.file("h.oitt");
};

// The report's FLIP is the metric of the two images the run wrote (image.png
// against the reference's sRGB codes), at the default 67.02 pixels per degree.
TEST_F(CliRunFlip, ReportAndFlipPngHoldTheFlipOfTheWrittenImages) {
  const std::string out = dir_.file("wboit");
  CliResult r = runOitsim("run --mode functional --algo wboit --trace " + trace_ + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("algorithm   wboit (format fp32, weight eq. 10), mode functional"), std::string::npos)
      << r.output;
  const nlohmann::json j = readJson(out + "/report.json");
  const auto& f = j["image"]["metrics"]["flip"];
  EXPECT_EQ(j["image"]["files"]["flip_png"], "flip.png");
  EXPECT_DOUBLE_EQ(f["ppd"].get<double>(), model::kFlipDefaultPpd);
  const model::FlipMap want =
      model::ldrFlip(model::toSrgb8Image(model::readPfm(out + "/reference.pfm")), model::readPng(out + "/image.png"));
  EXPECT_DOUBLE_EQ(f["mean"].get<double>(), want.stats.mean);
  EXPECT_DOUBLE_EQ(f["weighted_median"].get<double>(), want.stats.weighted_median);
  EXPECT_DOUBLE_EQ(f["weighted_q1"].get<double>(), want.stats.weighted_q1);
  EXPECT_DOUBLE_EQ(f["weighted_q3"].get<double>(), want.stats.weighted_q3);
  EXPECT_DOUBLE_EQ(f["max"].get<double>(), want.stats.max);
  EXPECT_GT(want.stats.mean, 0.0) << "wboit is approximate on hair";
  EXPECT_NE(r.output.find(fmt::format("FLIP at 67.02 px/degree: mean {:.5f}", want.stats.mean)), std::string::npos)
      << r.output;
  // flip.png: the map (its first 54 rows, magma of the error) and the 20-row scale.
  const model::Srgb8Image png = model::readPng(out + "/flip.png");
  ASSERT_EQ(png.width, 96u);
  ASSERT_EQ(png.height, 54u + model::kFlipScaleRows);
  size_t same = 0;
  for (size_t i = 0; i < want.error.size(); ++i) {
    uint8_t c[3];
    model::magmaSrgb8(want.error[i], c);
    same += png.rgb[3 * i] == c[0] && png.rgb[3 * i + 1] == c[1] && png.rgb[3 * i + 2] == c[2];
  }
  EXPECT_EQ(same, want.error.size());
}

TEST_F(CliRunFlip, PpdChangesTheErrorAndIsRecorded) {
  const std::string a = dir_.file("ppd67"), b = dir_.file("ppd20");
  ASSERT_EQ(runOitsim("run -q --mode functional --algo mlab --layers 1 --trace " + trace_ + " --out " + a).exit_code, 0);
  ASSERT_EQ(runOitsim("run -q --mode functional --algo mlab --layers 1 --ppd 20 --trace " + trace_ + " --out " + b)
                .exit_code,
            0);
  const auto fa = readJson(a + "/report.json")["image"]["metrics"]["flip"];
  const auto fb = readJson(b + "/report.json")["image"]["metrics"]["flip"];
  EXPECT_EQ(fb["ppd"].get<double>(), 20.0);
  // Fewer pixels per degree: each pixel spans more of the eye's field, so the
  // contrast sensitivity filters blur less and a difference shows more.
  EXPECT_GT(fb["mean"].get<double>(), fa["mean"].get<double>());
}

TEST_F(CliRunFlip, BadPpdIsOneErrorAndWritesNothing) {
  for (const char* bad : {"0", "-3", "nan", "20000"}) {
    const std::string out = dir_.file(std::string("bad") + bad);
    CliResult r = runOitsim("run -q --mode functional --ppd " + std::string(bad) + " --trace " + trace_ + " --out " + out);
    EXPECT_EQ(r.exit_code, 1) << bad << r.output;
    EXPECT_EQ(lines(r.output).size(), 1u) << r.output;
    EXPECT_NE(r.output.find("--ppd"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out + "/flip.png"));
    EXPECT_FALSE(fs::exists(out + "/report.json"));
  }
}

// abuffer uses none of k, bits, samples, weight, seed; its nodes store their
// colour in the format, so its summary names the format only (it said
// "abuffer (k=4, format fp32)"). With a pool that holds every fragment and
// fp32 nodes it is the exact reference (FLIP 0).
// Counts in the summary take their noun in number: adaptive reads the trace
// twice (its two passes), one-partition runs say "1 partition".
TEST_F(CliRunFlip, SummaryCountsAgreeInNumber) {
  CliResult r = runOitsim("run --algo adaptive --layers 2 --set partitions.count=1 --reference none --trace " + trace_ +
                          " --out " + dir_.file("adaptive"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(", 2 passes over the trace"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" MHz, 1 partition, bound by "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("(s)"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("(es)"), std::string::npos) << r.output;
}

TEST_F(CliRunFlip, SummaryShowsOnlyTheSettingsTheAlgorithmUses) {
  CliResult r = runOitsim("run --mode functional --algo abuffer --layers 2 --set abuffer.nodes_per_pixel=64 --trace " +
                          trace_ + " --out " + dir_.file("abuffer"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("algorithm   abuffer (format fp32), mode functional, 1 pass over the trace"),
            std::string::npos)
      << r.output;
  const nlohmann::json j = readJson(dir_.file("abuffer") + "/report.json");
  EXPECT_EQ(j["config"]["ignored_settings"], nlohmann::json({"layers", "bits", "samples", "weight", "seed"}));
  EXPECT_EQ(j["fragments"]["dropped_pool_full"].get<uint64_t>(), 0u);
  EXPECT_EQ(j["image"]["metrics"]["flip"]["mean"].get<double>(), 0.0);
  r = runOitsim("run --mode functional --algo mlab --layers 2 --trace " + trace_ + " --out " + dir_.file("mlab"));
  EXPECT_NE(r.output.find("algorithm   mlab (k=2, format fp32), mode functional"), std::string::npos) << r.output;
}

// The A-buffer's preallocated pool: 96 x 54 pixels, 1 node per pixel = 5184
// nodes; the fragments past them are dropped, counted and visible in the
// image's error, in both modes alike.
TEST_F(CliRunFlip, AbufferPoolOverflowIsCountedAndVisible) {
  for (const char* mode : {"functional", "timing"}) {
    const std::string out = dir_.file(std::string("pool-") + mode);
    CliResult r = runOitsim(std::string("run -q --mode ") + mode +
                            " --algo abuffer --set abuffer.nodes_per_pixel=1 --trace " + trace_ + " --out " + out);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = readJson(out + "/report.json");
    EXPECT_EQ(j["fragments"]["stored"].get<uint64_t>(), 96u * 54u) << mode;
    EXPECT_EQ(j["fragments"]["dropped_pool_full"].get<uint64_t>(),
              j["fragments"]["in"].get<uint64_t>() - j["fragments"]["opaque"].get<uint64_t>() -
                  j["fragments"]["culled_by_depth"].get<uint64_t>() - 96u * 54u)
        << mode;
    EXPECT_GT(j["image"]["metrics"]["flip"]["mean"].get<double>(), 0.0) << mode;
    EXPECT_EQ(j["config"]["abuffer"]["pool_nodes"].get<uint64_t>(), 96u * 54u) << mode;
  }
}

// A pool too small for the heads, or a zero budget: one line naming the
// parameter, exit 1, nothing written.
TEST_F(CliRunFlip, BadAbufferBudgetsAreOneLineNamingTheParameter) {
  const std::pair<const char*, const char*> cases[] = {
      {"abuffer.pool_bytes=1000", "abuffer.pool_bytes 1000 cannot hold the heads (20736 B for 96 x 54 pixels)"},
      {"abuffer.nodes_per_pixel=0", "abuffer.nodes_per_pixel"},
      {"abuffer.max_sorted=0", "abuffer.max_sorted"},
      {"abuffer.atomics_per_clock=0", "abuffer.atomics_per_clock"},
  };
  for (const auto& [set, want] : cases) {
    for (const char* mode : {"functional", "timing"}) {
      const std::string out = dir_.file(std::string("bad-") + mode);
      CliResult r = runOitsim(std::string("run -q --mode ") + mode + " --algo abuffer --set " + set + " --trace " +
                              trace_ + " --out " + out);
      EXPECT_EQ(r.exit_code, 1) << set << r.output;
      EXPECT_EQ(lines(r.output).size(), 1u) << set << r.output;
      EXPECT_NE(r.output.find(want), std::string::npos) << set << r.output;
      EXPECT_FALSE(fs::exists(out + "/report.json")) << set;
    }
  }
}

}  // namespace
}  // namespace oit::test
