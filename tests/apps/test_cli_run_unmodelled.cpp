// `oitsim run` on a version 2 trace whose draw table holds draws of blend modes the
// model does not blend (additive, multiplicative): they are reported and counted
// as not modelled, never replayed as over-blending (FORMAT.md 3.1, REPORT.md).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

// A 4 x 2 frame: draw 0 over-blends two fragments (its records); draws 1 and 3 are
// additive (7 + 4 fragments), draw 2 multiplicative (5), with no records (v2 keeps
// them out). Draw 0's two records are the only ones.
constexpr const char* kHead =
    "# width 4\n# height 2\n"
    "# draw 0 transparent \"glDrawArrays #0 program 3\"\n";
constexpr const char* kOverState = "# draw-state 0 over test 0x0201 0x8006 0x0302 0x0303 0x8006 0x0302 0x0303 2\n";
constexpr const char* kUnmodelled =
    "# draw 1 transparent \"glDrawArrays #1 program 4\"\n"
    "# draw-state 1 additive off 0x0000 0x8006 0x0001 0x0001 0x8006 0x0001 0x0001 7\n"
    "# draw 2 transparent \"glDrawArrays #2 program 5\"\n"
    "# draw-state 2 multiplicative off 0x0000 0x8006 0x0306 0x0000 0x8006 0x0306 0x0000 5\n"
    "# draw 3 transparent \"glDrawArrays #3 program 5\"\n"
    "# draw-state 3 additive off 0x0000 0x8006 0x0302 0x0001 0x8006 0x0302 0x0001 4\n";
constexpr const char* kRows =
    "draw,prim,x,y,z,r,g,b,a,opaque\n"
    "0,0,1,1,0.5,1,0,0,0.5,0\n"
    "0,0,2,1,0.5,0,1,0,0.5,0\n";

class CliRunUnmodelled : public ::testing::Test {
 protected:
  TempDir dir_{"cli_run_unmodelled"};
  CliResult run(const std::string& trace, const std::string& out) {
    return runOitsim("run --trace " + trace + " --mode functional --algo mlab --out " + out);
  }
};

TEST_F(CliRunUnmodelled, AdditiveAndMultiplicativeDrawsAreCountedNotBlended) {
  const std::string v2 = dir_.file("v2.csv"), v1 = dir_.file("v1.csv");
  writeText(v2, std::string("# oitsim-trace v2\n") + kHead + kOverState + kUnmodelled + kRows);
  writeText(v1, std::string("# oitsim-trace v1\n") + kHead + kRows);  // draw 0 alone
  CliResult r = run(v2, dir_.file("out2"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("not modelled 3 draws, 16 fragments: additive 2 draws (11 fragments), multiplicative 1 "
                          "draw (5 fragments)"),
            std::string::npos)
      << r.output;
  const nlohmann::json j = nlohmann::json::parse(readText(dir_.path() / "out2" / "report.json"));
  const nlohmann::json& f = j.at("fragments");
  EXPECT_EQ(f.at("in"), 2);  // the records: draw 0's only
  EXPECT_EQ(f.at("stored"), 2);
  EXPECT_EQ(f.at("not_modelled").at("draws"), 3);
  EXPECT_EQ(f.at("not_modelled").at("fragments"), 16);  // 7 + 5 + 4
  EXPECT_EQ(f.at("not_modelled").at("by_blend_mode").at("additive").at("fragments"), 11);
  EXPECT_EQ(f.at("not_modelled").at("by_blend_mode").at("multiplicative").at("draws"), 1);
  EXPECT_FALSE(f.at("not_modelled").at("by_blend_mode").contains("over"));
  CliResult info = runOitsim("info " + v2);
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("not modelled 3 draws, 16 fragments"), std::string::npos) << info.output;
  // Nothing of the unmodelled draws reaches the image: it is draw 0's alone, bit for bit.
  CliResult r1 = run(v1, dir_.file("out1"));
  ASSERT_EQ(r1.exit_code, 0) << r1.output;
  EXPECT_EQ(r1.output.find("not modelled"), std::string::npos) << r1.output;
  EXPECT_EQ(readText(dir_.path() / "out2" / "image.pfm"), readText(dir_.path() / "out1" / "image.pfm"));
}

TEST_F(CliRunUnmodelled, AModelledVersionTwoTraceHasNone) {
  const std::string v2 = dir_.file("over.csv");
  writeText(v2, std::string("# oitsim-trace v2\n") + kHead + kOverState + kRows);
  CliResult r = run(v2, dir_.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("not modelled"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(readText(dir_.path() / "out" / "report.json"));
  EXPECT_EQ(j.at("fragments").at("not_modelled").at("draws"), 0);
  EXPECT_EQ(j.at("fragments").at("not_modelled").at("fragments"), 0);
  EXPECT_TRUE(j.at("fragments").at("not_modelled").at("by_blend_mode").empty());
}

}  // namespace
}  // namespace oit::test
