// The Slurm job array of a sweep.
#include "reports/SlurmScript.hpp"

#include <fmt/core.h>

#include <regex>
#include <stdexcept>

namespace oit::sweep {

bool isSlurmTime(const std::string& t) {
  static const std::regex kTime(
      R"(^(\d+|\d+:\d{1,2}|\d+:\d{1,2}:\d{1,2}|\d+-\d{1,2}|\d+-\d{1,2}:\d{1,2}|\d+-\d{1,2}:\d{1,2}:\d{1,2})$)");
  return t.size() <= 32 && std::regex_match(t, kTime);
}

bool isSlurmMemory(const std::string& m) {
  static const std::regex kMem(R"(^[1-9]\d{0,12}[KMGT]?$)");
  return std::regex_match(m, kMem);
}

void checkSlurmOptions(const SlurmOptions& o, bool points_per_task_given) {
  if (points_per_task_given && o.points_per_task == 0)
    throw std::invalid_argument("--points-per-task 0: expected a positive number of points per Slurm array task");
  if (!o.time.empty() && !isSlurmTime(o.time))
    throw std::invalid_argument("--time " + o.time +
                                ": not a Slurm time limit (expected minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM or "
                                "D-HH:MM:SS, e.g. 30 or 2:00:00)");
  if (!o.mem.empty() && !isSlurmMemory(o.mem))
    throw std::invalid_argument("--mem " + o.mem +
                                ": not a Slurm memory size (expected a whole number with an optional K, M, G or T "
                                "suffix, e.g. 2G)");
  if (o.partition.find_first_of(" \t\n\r'\"\\$`") != std::string::npos)
    throw std::invalid_argument("--partition " + o.partition + ": expected a partition name (no spaces or quotes)");
  for (const std::string& line : o.sbatch)
    if (line.empty() || line[0] != '-' || line.find_first_of("\n\r") != std::string::npos)
      throw std::invalid_argument("--sbatch '" + line +
                                  "': expected one sbatch option for a #SBATCH line, e.g. --account=NAME");
}

size_t defaultPointsPerTask(size_t points) {
  return points <= kMaxArrayTasks ? 1 : (points + kMaxArrayTasks - 1) / kMaxArrayTasks;
}

SlurmJob makeSlurmJob(const Plan& plan, const std::vector<size_t>& points, const SlurmOptions& o) {
  SlurmJob job;
  job.points_per_task = o.points_per_task ? o.points_per_task : defaultPointsPerTask(points.size());
  for (size_t at = 0; at < points.size(); at += job.points_per_task) {
    std::string line;
    for (size_t i = at; i < points.size() && i < at + job.points_per_task; ++i)
      line += fmt::format("{}{}", line.empty() ? "" : " ", points[i]);
    job.tasks += fmt::format("{}\n", line);
    ++job.task_count;
  }
  const std::string dir = plan.out.string();
  std::string options;
  if (!o.time.empty()) options += fmt::format("#SBATCH --time={}\n", o.time);
  if (!o.mem.empty()) options += fmt::format("#SBATCH --mem={}\n", o.mem);
  if (!o.partition.empty()) options += fmt::format("#SBATCH --partition={}\n", o.partition);
  for (const std::string& line : o.sbatch) options += fmt::format("#SBATCH {}\n", line);
  // A point that fails does not stop its task's other points; the task exits 1
  // if any failed, so Slurm marks it FAILED (resubmit with --array=T).
  job.script = fmt::format(
      "#!/bin/bash\n"
      "# Slurm job array made by `oitsim sweep --emit slurm` for {}:\n"
      "# {} point(s) in {} task(s) of up to {}; task T runs the commands.txt lines listed on line T+1\n"
      "# of slurm-tasks.txt. Submit: sbatch {}   Then merge: oitsim report {}\n"
      "#SBATCH --job-name=oitsim-sweep\n"
      "#SBATCH --array=0-{}\n"
      "#SBATCH --cpus-per-task=1\n"
      "#SBATCH --output={}/slurm-%A_%a.log\n"
      "{}"
      "set -uo pipefail\n"
      "points=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" {})\n"
      "failed=0\n"
      "for i in $points; do\n"
      "  line=$(sed -n \"$((i + 1))p\" {})\n"
      "  bash -c \"$line\" || failed=$((failed + 1))\n"
      "done\n"
      "[ \"$failed\" -eq 0 ]\n",
      plan.spec, points.size(), job.task_count, job.points_per_task, shellQuote(dir + "/sweep.slurm"),
      shellQuote(dir), job.task_count ? job.task_count - 1 : 0, dir, options,
      shellQuote(dir + "/slurm-tasks.txt"), shellQuote(dir + "/commands.txt"));
  return job;
}

}  // namespace oit::sweep
