// `oitsim sweep --emit slurm`: a job array whose tasks each run a chunk of the
// points still to run (DIR/slurm-tasks.txt line t: the commands.txt line
// numbers of task t), with the site's options passed through.
#pragma once

#include <string>
#include <vector>

#include "reports/SweepPlan.hpp"

namespace oit::sweep {

// Slurm's default MaxArraySize is 1001 (array indices 0..1000): the default
// chunking keeps an array to at most this many tasks.
inline constexpr size_t kMaxArrayTasks = 999;

struct SlurmOptions {
  size_t points_per_task = 0;  // 0: the smallest that keeps the array within kMaxArrayTasks
  std::string time;            // --time, a Slurm time limit ("" = the site's default)
  std::string mem;             // --mem, memory per node ("" = the site's default)
  std::string partition;       // --partition
  std::vector<std::string> sbatch;  // extra #SBATCH lines, e.g. "--account=gpu-arch"
};

// Checks every option before anything is created; throws std::invalid_argument
// naming the option and what was expected.
void checkSlurmOptions(const SlurmOptions& o, bool points_per_task_given);

// A Slurm time limit: minutes, minutes:seconds, hours:minutes:seconds,
// days-hours, days-hours:minutes or days-hours:minutes:seconds (sbatch(1)).
bool isSlurmTime(const std::string& t);
// A memory size: a whole number with an optional K, M, G or T suffix (sbatch --mem).
bool isSlurmMemory(const std::string& m);

// ceil(points / kMaxArrayTasks), at least 1.
size_t defaultPointsPerTask(size_t points);

struct SlurmJob {
  std::string script;  // DIR/sweep.slurm
  std::string tasks;   // DIR/slurm-tasks.txt
  size_t task_count = 0, points_per_task = 0;
};

// The job for the given points (indices into plan.points, in order).
SlurmJob makeSlurmJob(const Plan& plan, const std::vector<size_t>& points, const SlurmOptions& o);

}  // namespace oit::sweep
