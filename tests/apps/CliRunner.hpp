// Runs the built oitsim executable and captures its exit code and output.
#pragma once

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace oit::test {

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

inline std::string oitsimPath() { return std::string(OITSIM_BINARY_DIR) + "/apps/oitsim"; }

inline CliResult runOitsim(const std::string& args) {
  CliResult r;
  const std::string cmd = oitsimPath() + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// A fresh directory under the test's working directory, removed on destruction.
// The pid keeps tests that ctest runs in parallel processes apart.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::current_path() / ("tmp_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace oit::test
