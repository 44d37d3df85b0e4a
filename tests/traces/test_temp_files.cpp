// Temporary files are removed when the process is interrupted (SIGINT/SIGTERM),
// and temporary names stay within the file-name limit.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>

#include "traces/TempFiles.hpp"

namespace oit {
namespace {

namespace fs = std::filesystem;

TEST(TempFiles, AnInterruptRemovesRegisteredFilesAndStillKillsTheProcess) {
  for (int sig : {SIGINT, SIGTERM}) {
    const fs::path dir = fs::temp_directory_path() / ("oitsim_tempfiles_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string kept = (dir / "kept").string(), temp = (dir / "partial.tmp").string(),
                      gone = (dir / "unregistered.tmp").string();
    const pid_t pid = fork();
    if (pid == 0) {
      removeTempFilesOnSignals();
      for (const std::string& p : {kept, temp, gone}) std::ofstream(p) << "x";
      registerTempFile(temp);
      registerTempFile(gone);
      unregisterTempFile(gone);  // committed: it must stay
      std::raise(sig);
      _exit(0);  // not reached
    }
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << status;
    EXPECT_FALSE(fs::exists(temp)) << sig;
    EXPECT_TRUE(fs::exists(kept));
    EXPECT_TRUE(fs::exists(gone));
    fs::remove_all(dir);
  }
}

TEST(TempFiles, TemporaryNamesFitTheFileNameLimit) {
  const std::string dir = "/some/dir/";
  const std::string short_name = dir + "x.oitt";
  const std::string t = tempPathNextTo(short_name);
  EXPECT_EQ(t.rfind(short_name + ".tmp.", 0), 0u) << t;
  const std::string long_name = dir + std::string(245, 'b') + ".oitt";  // 250 bytes: valid
  const std::string l = tempPathNextTo(long_name);
  EXPECT_LE(fs::path(l).filename().string().size(), 255u) << l;
  EXPECT_EQ(fs::path(l).parent_path(), fs::path("/some/dir"));
}

}  // namespace
}  // namespace oit
