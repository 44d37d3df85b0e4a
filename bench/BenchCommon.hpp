// Shared by the benchmark programs: reading a trace into memory before
// anything is timed, CPU time of the process, and the CLI11 error exit.
#pragma once

#include <time.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "model/MemorySource.hpp"
#include "traces/TraceIO.hpp"

namespace oit::bench {

// The whole trace at `path` in memory (openTrace validates it; its errors name
// the file and offset). Reading is never part of a timed section.
inline std::unique_ptr<model::MemorySource> loadTrace(const std::string& path) {
  auto file = openTrace(path);
  std::vector<Fragment> fs;
  fs.reserve(file->header().fragment_count);
  for (auto b = file->next(); !b.empty(); b = file->next()) fs.insert(fs.end(), b.begin(), b.end());
  return std::make_unique<model::MemorySource>(file->header(), std::move(fs));
}

// CPU time of this process: on a shared machine it varies less than wall time.
inline double cpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace oit::bench
