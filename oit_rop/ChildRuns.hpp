// Timing runs in forked child processes. SystemC elaborates once per process
// (runTiming() once per process), so runs side by side, or more than one run
// in a process, each need a process of their own: a job runs in a fork()ed
// child and sends its TimingResult (stats, counts, image, wall seconds) back
// through a pipe, with its progress on the way.
//
// runTimingSeeds() replays one frame with N shader-latency seeds (input.seed,
// input.seed + 1, ...), every core busy: `oitsim run --seeds N` measures
// flicker across them (model/Flicker.hpp).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "model/OitAlgorithm.hpp"
#include "oit_rop/TimingRun.hpp"
#include "traces/TraceIO.hpp"

namespace oit::rop {

// A job: runs in the child, reporting its progress (fraction in [0, 1], what runs).
using TimingJob = std::function<TimingResult(const std::function<void(double, const std::string&)>& progress)>;

struct ChildRunOptions {
  unsigned parallel = 1;  // children at a time (at least 1)
  // The mean fraction done over all jobs, in the parent (at most every 100 ms,
  // and at each job's end).
  std::function<void(double)> progress;
  // Names job i in its error message ("job i" by default; nothing when there is one job).
  std::function<std::string(size_t)> name;
};

// Runs every job in a child process of its own, `options.parallel` at a time,
// and returns their results in job order. A job that throws, or a child that
// dies, stops the others (SIGTERM to each by its pid, then waited for) and is
// rethrown as std::runtime_error("<name>: <the job's message>"). Flushes
// stdout and stderr before each fork. The children are registered with
// registerChildProcess (traces/TempFiles.hpp), so a signal that interrupts
// this process reaches them too.
std::vector<TimingResult> runTimingInChildren(const std::vector<TimingJob>& jobs, const ChildRunOptions& options);

// The cores this process may run on (sched_getaffinity; at least 1).
unsigned usableCores();

struct SeedRunsRequest {
  RopConfig cfg;       // seed i runs with input.seed = cfg.input.seed + i
  unsigned seeds = 1;  // >= 1
  unsigned parallel = 0;  // children at a time; 0 = usableCores()
  // Called in each child: its own trace reader (a reader opened before the
  // fork would share its file offset with the parent's) and algorithm.
  std::function<std::unique_ptr<FragmentSource>()> open_trace;
  std::function<std::unique_ptr<model::OitAlgorithm>()> make_algorithm;
  TimingOptions options;  // clear colour; vcd_path: seed 0's run only; progress: unused (see below)
  std::function<void(double)> progress;  // mean fraction done over the seeds
};

// Results in seed order (result i from input.seed = cfg.input.seed + i).
// Throws std::invalid_argument when seeds is 0.
std::vector<TimingResult> runTimingSeeds(const SeedRunsRequest& request);

}  // namespace oit::rop
