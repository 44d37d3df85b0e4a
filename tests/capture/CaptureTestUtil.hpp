// Helpers shared by the capture tests.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "traces/TraceIO.hpp"

namespace oit::capture::test_util {

// Collects what a capture writes.
class VectorSink : public FragmentSink {
 public:
  std::vector<Fragment> fragments;
  void write(const Fragment& f) override { fragments.push_back(f); }
  void write(std::span<const Fragment> fs) override { fragments.insert(fragments.end(), fs.begin(), fs.end()); }
  void commit() override {}
  uint64_t written() const override { return fragments.size(); }
};

// Runs a shell command, appends its stdout and stderr to *out; its exit code (-1
// when it did not exit).
inline int runCommand(const std::string& command, std::string* out) {
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out->append(buf, n);
  const int status = pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace oit::capture::test_util
