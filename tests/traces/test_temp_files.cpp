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

// A pid that surely belongs to no process: a child that has exited and been reaped.
int deadPid() {
  const pid_t pid = fork();
  if (pid == 0) _exit(0);
  int status = 0;
  waitpid(pid, &status, 0);
  return pid;
}

TEST(TempFiles, PidAfterPrefixReadsOnlyWholeNumbers) {
  EXPECT_EQ(pidAfterPrefix("a.oitt.tmp.123.4", "a.oitt.tmp."), 123);
  EXPECT_EQ(pidAfterPrefix("a.oitt.tmp.123", "a.oitt.tmp."), 123);
  EXPECT_EQ(pidAfterPrefix("a.oitt.tmp.12x", "a.oitt.tmp."), 0);
  EXPECT_EQ(pidAfterPrefix("a.oitt.tmp.", "a.oitt.tmp."), 0);
  EXPECT_EQ(pidAfterPrefix("b.oitt.tmp.123.4", "a.oitt.tmp."), 0);
  EXPECT_EQ(pidAfterPrefix("a.oitt.tmp.-5.4", "a.oitt.tmp."), 0);
}

// What a writer killed by SIGKILL left (no handler runs): the next writer of
// the same file removes the temporaries of processes that are gone, and only
// those: a live process's temporary and other files stay.
TEST(TempFiles, AWriterKilledOutrightLeavesNothingForLong) {
  const fs::path dir = fs::temp_directory_path() / ("oitsim_abandoned_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // A writer that is killed while it writes (its temporary exists).
  const std::string target = (dir / "t.bin").string();
  const pid_t writer = fork();
  if (writer == 0) {  // an atomic writer's temporary name: "<path>.tmp.<pid>.<n>"
    std::ofstream(target + ".tmp." + std::to_string(::getpid()) + ".0") << "half";
    for (;;) pause();
  }
  const std::string killed_tmp = target + ".tmp." + std::to_string(writer) + ".0";
  for (int i = 0; i < 500 && !fs::exists(killed_tmp); ++i) usleep(10000);
  ::kill(writer, SIGKILL);
  waitpid(writer, nullptr, 0);
  ASSERT_TRUE(fs::exists(killed_tmp));
  const std::string dead_long = (dir / (".oitsim.tmp." + std::to_string(deadPid()) + ".3")).string();
  const std::string live = target + ".tmp." + std::to_string(::getppid()) + ".0";  // a live process
  const std::string other = (dir / ("u.bin.tmp." + std::to_string(deadPid()) + ".0")).string();  // another target
  const std::string user = (dir / "t.bin.tmp.notes").string();
  for (const std::string& p : {dead_long, live, other, user}) std::ofstream(p) << "x";
  // The next writer of t.bin takes its temporary name: the leftovers go then.
  const std::string next = tempPathNextTo(target);
  EXPECT_EQ(next.rfind(target + ".tmp." + std::to_string(::getpid()) + ".", 0), 0u) << next;
  EXPECT_FALSE(fs::exists(killed_tmp));
  EXPECT_FALSE(fs::exists(dead_long));
  EXPECT_TRUE(fs::exists(live));
  EXPECT_TRUE(fs::exists(other));
  EXPECT_TRUE(fs::exists(user));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace oit
