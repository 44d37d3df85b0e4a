// The oitsim executable does not need the GL libraries: only `capture` loads
// libEGL.so.1 and libOpenGL.so.0, at run time (traces/capture/GlEntryPoints.cpp).
// Checked on a machine that has them by putting unloadable files of those names
// first on LD_LIBRARY_PATH: had the executable linked them, the dynamic loader
// would refuse to start it ("invalid ELF header") for every command.
#include <gtest/gtest.h>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

TEST(CliWithoutGl, RunAndSweepStartWithoutGlAndCaptureSaysWhatIsMissing) {
  TempDir d("without_gl");
  for (const char* lib : {"libEGL.so.1", "libOpenGL.so.0", "libGL.so.1", "libGLX.so.0", "libGLdispatch.so.0"})
    writeText(d.file(lib), "not a shared library\n");
  const std::string env = "LD_LIBRARY_PATH=" + d.path().string() + " ";
  CliResult r = runShell(env + oitsimPath() + " gen glass --width 32 --height 24 -q -o " + d.file("g.oitt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = runShell(env + oitsimPath() + " run -q --trace " + d.file("g.oitt") + " --out " + d.file("run"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  writeText(d.file("s.json"), R"({"traces": ["g.oitt"], "base": {"mode": "functional"}, "axes": {"algo": ["mlab"]}})");
  r = runShell(env + oitsimPath() + " sweep -q " + d.file("s.json") + " --out " + d.file("sw"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // capture needs them: one line naming the library and what to install.
  r = runShell(env + oitsimPath() + " capture --mesh bunny --width 32 --height 24 -o " + d.file("c.oitt"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("oitsim: error: cannot load libEGL.so.1 ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("apt-get install libegl1 libopengl0"), std::string::npos) << r.output;
  EXPECT_EQ(lines(r.output).size(), 1u) << r.output;
}

}  // namespace
}  // namespace oit::test
