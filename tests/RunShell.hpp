// Runs a shell command and captures its exit code and output: shared by the CLI
// tests (apps/CliRunner.hpp) and the capture tests (capture/CaptureTestUtil.hpp).
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace oit::test {

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a shell command; exit code -1 if it did not exit normally.
inline CliResult runShell(const std::string& command) {
  CliResult r;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace oit::test
