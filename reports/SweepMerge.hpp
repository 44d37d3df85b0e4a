// Merging a sweep: DIR/results.csv and DIR/results.json rebuilt from
// DIR/plan.json and the points' folders alone, so points run anywhere (this
// machine, a Slurm array) merge the same way. Formats: reports/SWEEP.md.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace oit::sweep {

struct MergeSummary {
  size_t points = 0, ok = 0, failed = 0, not_run = 0;
  std::vector<std::pair<std::string, std::string>> failures;  // id, error
  std::vector<std::string> not_run_ids;
  std::filesystem::path csv, json;
};

// A point is `ok` (a report.json), `failed` (its process exited non-zero, or it
// started and left no report.json; error = the tail of its stderr) or `not
// run` (no status.json, stderr.txt or report.json yet). Writes both tables,
// whole or not at all. Throws std::invalid_argument when DIR has no plan.json.
MergeSummary mergeSweep(const std::filesystem::path& dir);

// "sweep: 18 points, 17 ok, 1 failed; results A and B", then one line per
// failure and a line naming the points not run yet (at most `list` of them).
std::string mergeSummaryText(const MergeSummary& s, size_t list = 10);

// A report flattened to dotted keys (arrays of objects by index, arrays of
// numbers as JSON text); the time series' samples stay out.
void flattenReport(const nlohmann::json& j, const std::string& prefix, nlohmann::json& out);

}  // namespace oit::sweep
