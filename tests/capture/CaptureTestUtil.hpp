// Helpers shared by the capture tests.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "RunShell.hpp"
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

// Runs a shell command (RunShell.hpp), appends its stdout and stderr to *out; its
// exit code (-1 when it did not exit).
inline int runCommand(const std::string& command, std::string* out) {
  const test::CliResult r = test::runShell(command);
  out->append(r.output);
  return r.exit_code;
}

}  // namespace oit::capture::test_util
