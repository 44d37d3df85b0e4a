// End-to-end tests of `oitsim gen` and the option checks of `oitsim capture`
// (those that run before any GL) on the real executable.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

// A tetrahedron in OFF form.
const char* kOff =
    "OFF\n4 4 0\n"
    "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
    "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

// -o must never be the mesh being read (same path, another spelling, a symlink).
TEST(CliGen, OutputNeverOverwritesTheMesh) {
  TempDir dir("gen_out_is_mesh");
  writeText(dir.file("my.off"), kOff);
  std::filesystem::create_symlink("my.off", dir.path() / "link.off");
  ASSERT_EQ(runOitsim("gen mesh -q --width 32 --height 32 --mesh " + dir.file("my.off") + " -o " + dir.file("t.oitt"))
                .exit_code,
            0);
  for (const std::string& out : {dir.file("my.off"), (dir.path() / "." / "my.off").string(), dir.file("link.off")}) {
    CliResult r = runOitsim("gen mesh -q --width 32 --height 32 --mesh " + dir.file("my.off") + " -o " + out);
    EXPECT_EQ(r.exit_code, 1) << out << ": " << r.output;
    EXPECT_NE(r.output.find("-o " + out + ": is the input mesh --mesh " + dir.file("my.off")), std::string::npos)
        << r.output;
    EXPECT_EQ(lines(r.output).size(), 1u) << r.output;
  }
  EXPECT_EQ(readText(dir.file("my.off")), kOff);
}

// capture refuses the same before it starts GL (so this runs without a GPU stack).
TEST(CliCapture, OutputNeverOverwritesTheMesh) {
  TempDir dir("capture_out_is_mesh");
  writeText(dir.file("my.off"), kOff);
  CliResult r = runOitsim("capture -q --mesh " + dir.file("my.off") + " -o " + dir.file("my.off"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("-o " + dir.file("my.off") + ": is the input mesh"), std::string::npos) << r.output;
  EXPECT_EQ(readText(dir.file("my.off")), kOff);
}

// -o is checked before the scene is built or GL is started: an empty path, a
// directory, a missing folder are one-line errors naming -o (gen -o "" built
// the whole scene, then failed with ": cannot rename temporary file ...").
TEST(CliGen, OutputPathIsCheckedFirst) {
  TempDir dir("gen_bad_output");
  struct Case {
    std::string output, message;
  };
  const Case cases[] = {
      {"''", "-o: expected a file name, got an empty path"},
      {dir.file(""), "-o " + dir.file("") + ": is a directory, expected a file name"},
      {dir.file("sub/"), "-o " + dir.file("sub/") + ": expected a file name, got a folder path"},
      {dir.file("missing/t.oitt"), "-o " + dir.file("missing/t.oitt") + ": folder " + dir.file("missing") +
                                       " does not exist"},
  };
  for (const Case& c : cases) {
    for (const std::string& cmd : {"gen particles -q --density 50 -o " + c.output, "capture -q --mesh bunny -o " + c.output}) {
      CliResult r = runOitsim(cmd);
      EXPECT_EQ(r.exit_code, 1) << cmd << "\n" << r.output;
      EXPECT_EQ(r.output, "oitsim: error: " + c.message + "\n") << cmd;
    }
  }
  std::filesystem::create_directory(dir.file("afile.oitt"));
  CliResult r = runOitsim("gen glass -q -o " + dir.file("afile.oitt"));
  EXPECT_NE(r.output.find("-o " + dir.file("afile.oitt") + ": is a directory"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace oit::test
