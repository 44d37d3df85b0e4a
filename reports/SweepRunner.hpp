// Running a sweep's plan on this machine: generating its traces, deciding which
// points still need to run (a resumed sweep keeps finished ones), and running
// each point as its own `oitsim run` process, `jobs` at a time.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "reports/SweepPlan.hpp"

namespace oit::sweep {

// Progress and messages (the command decides where they go and whether at all).
using Say = std::function<void(const std::string&)>;

struct Outcome {
  int exit_code = -1;
  double wall_seconds = 0.0;
};

// Runs exe with args, stdout and stderr into files; waits. An interrupt of this
// process reaches the child too (traces/TempFiles.hpp registerChildProcess).
Outcome spawnAndWait(const std::string& exe, const std::vector<std::string>& args,
                     const std::filesystem::path& out_file, const std::filesystem::path& err_file);

// The last max_chars of a file, trailing blanks removed; its first max_lines lines.
std::string tailOf(const std::filesystem::path& file, size_t max_chars = 600);
std::string headOf(const std::filesystem::path& file, size_t max_lines);

// Generates the plan's traces that are missing or whose generator arguments
// changed since `earlier_stamps` (every one with `force`), `jobs` at a time.
// When a generator fails, the files this step made are removed (and the sweep
// folder itself when `out_existed` is false) and std::runtime_error lists each
// failed generator's command, exit code and first lines of error output.
void generateTraces(const Plan& plan, const std::map<std::string, std::string>& earlier_stamps, bool force,
                    unsigned jobs, bool out_existed, const Say& say);

// The points that must run: every one with `force`; otherwise those without a
// finished result of this very run, i.e. earlier plan with the same id and
// arguments, the same trace stamp, a report.json and no failed status.json.
// Their folders are emptied; finished points keep theirs.
struct PendingPoints {
  std::vector<size_t> indices;  // into plan.points
  size_t kept = 0;              // finished earlier, not run again
};
PendingPoints preparePoints(const Plan& plan, const Plan* earlier, const std::map<std::string, std::string>& earlier_stamps,
                            bool force);

// Runs the given points, `jobs` at a time, one progress line per finished point
// (with the error's tail for a failure); each point's status.json records its
// exit code and wall seconds.
void runPoints(const Plan& plan, const std::vector<size_t>& indices, unsigned jobs, const Say& say);

}  // namespace oit::sweep
