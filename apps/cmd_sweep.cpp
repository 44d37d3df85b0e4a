// oitsim sweep SPEC --out DIR: run every point of a parameter sweep as its own
// `oitsim run` process, in parallel, or emit a Slurm job array; then merge the
// points into one table. The planning, running, merging and Slurm emission are
// library code in reports/Sweep*.cpp and reports/SlurmScript.cpp; this file
// checks the options and calls them. Spec, files and exit codes: reports/SWEEP.md.
#include <fmt/core.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>

#include "apps/Commands.hpp"
#include "reports/SlurmScript.hpp"
#include "reports/SweepMerge.hpp"
#include "reports/SweepPlan.hpp"
#include "reports/SweepRunner.hpp"
#include "reports/AtomicFile.hpp"

namespace oit::cli {

namespace fs = std::filesystem;

std::string selfExecutable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the oitsim executable via /proc/self/exe: " + ec.message());
  return p.string();
}

namespace {

struct SweepArgs {
  std::string spec, out, emit;
  unsigned jobs = 0;
  bool quiet = false, force = false;
  sweep::SlurmOptions slurm;
  bool points_per_task_given = false;
};

// The Slurm options mean nothing without --emit slurm: refused, not ignored.
void checkOptions(const SweepArgs& a, const CLI::App& cmd) {
  if (a.emit != "slurm")
    for (const char* name : {"--points-per-task", "--time", "--mem", "--partition", "--sbatch"})
      if (cmd.get_option(name)->count() > 0)
        throw std::invalid_argument(fmt::format("{} is an option of --emit slurm (add it, or drop {})", name, name));
  sweep::checkSlurmOptions(a.slurm, a.points_per_task_given);
}

void runSweep(const SweepArgs& a) {
  const sweep::ojson spec = sweep::loadSpec(a.spec);
  checkOutputFolder("--out", a.out);  // as `oitsim run --out`: before anything is created
  const fs::path out = fs::absolute(a.out);
  const sweep::Plan plan = sweep::planSweep(spec, a.spec, out, selfExecutable());
  const unsigned jobs = a.jobs ? a.jobs : std::max(1u, std::thread::hardware_concurrency());
  std::mutex mu;
  const sweep::Say say = [&](const std::string& s) {
    if (a.quiet) return;
    std::lock_guard<std::mutex> lock(mu);
    fmt::print(stderr, "{}\n", s);
  };
  if (const std::string dups = sweep::duplicatesLine(plan); !dups.empty()) say("sweep: " + dups);

  // An earlier sweep into this folder: its finished points are kept when they
  // are this plan's runs too (same command, same trace), unless --force.
  std::optional<sweep::Plan> earlier;
  std::map<std::string, std::string> earlier_stamps;
  if (fs::exists(out / "plan.json")) {
    try {
      earlier = sweep::readPlan(out);
      earlier_stamps = sweep::readTraceStamps(out);
    } catch (const std::invalid_argument&) {
      earlier.reset();  // unreadable: nothing is reused
    }
  }
  // Traces first (points need them), before the plan or any point folder is
  // written; a failed generator leaves the folder as it was.
  sweep::generateTraces(plan, earlier_stamps, a.force, jobs, fs::exists(out), say);
  fs::create_directories(out / "points");
  const sweep::PendingPoints pending = sweep::preparePoints(plan, earlier ? &*earlier : nullptr, earlier_stamps, a.force);
  // Nothing of an earlier sweep may pass for this one's tables or job, also if
  // this one is interrupted (a stale sweep.slurm would submit the earlier plan).
  for (const char* name : {"results.csv", "results.json", "report.html", "speed.json", "sweep.slurm", "slurm-tasks.txt"})
    fs::remove(out / name);
  sweep::writePlanFiles(plan);
  if (pending.kept)
    say(fmt::format("sweep: {} of {} points finished earlier with the same command and trace: kept (--force reruns "
                    "them)",
                    pending.kept, plan.points.size()));

  if (a.emit == "slurm") {
    if (pending.indices.empty()) {
      fmt::print("every one of the {} points has finished: no Slurm job written; oitsim report {} merges them\n",
                 plan.points.size(), out.string());
      return;
    }
    const sweep::SlurmJob job = sweep::makeSlurmJob(plan, pending.indices, a.slurm);
    reports::writeFileAtomically((out / "slurm-tasks.txt").string(), job.tasks);
    reports::writeFileAtomically((out / "sweep.slurm").string(), job.script);
    fmt::print("wrote {} ({} tasks of up to {} points, {} points in all), {} and {}; nothing was run\n",
               (out / "sweep.slurm").string(), job.task_count, job.points_per_task, pending.indices.size(),
               (out / "slurm-tasks.txt").string(), (out / "commands.txt").string());
    if (a.slurm.time.empty() || a.slurm.mem.empty())
      fmt::print("  no {}: the site's defaults apply (sbatch options on the command line override the script's)\n",
                 a.slurm.time.empty() && a.slurm.mem.empty() ? "--time or --mem" : a.slurm.time.empty() ? "--time" : "--mem");
    return;
  }

  say(fmt::format("sweep {}: {} points ({} traces), {} to run, {} jobs, into {}", a.spec, plan.points.size(),
                  plan.traces.size(), pending.indices.size(), jobs, out.string()));
  sweep::runPoints(plan, pending.indices, jobs, say);
  const sweep::MergeSummary sum = sweep::mergeSweep(out);
  if (!a.quiet) fmt::print("{}", sweep::mergeSummaryText(sum));
  if (sum.failed || sum.not_run) {
    std::fflush(stdout);
    std::fflush(stderr);
    std::exit(2);  // the sweep finished but some points failed (reports/SWEEP.md)
  }
}

}  // namespace

void addSweepCommand(CLI::App& app) {
  auto a = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sweep", "Run a parameter sweep (JSON or YAML spec; reports/SWEEP.md): one `oitsim run` per point, in parallel; "
               "points finished by an earlier sweep into the same folder are kept; exit 2 if any point failed");
  cmd->add_option("spec", a->spec, "Sweep spec (.json, or .yaml/.yml with python3-yaml)")->required();
  cmd->add_option("--out,-o", a->out, "Output folder: results.csv, results.json, plan.json, points/<id>/")->required();
  cmd->add_option("--jobs,-j", a->jobs, "Points run at once (default: number of cores)");
  cmd->add_flag("--force", a->force, "Run every point (and generate every trace) again, finished or not");
  cmd->add_option("--emit", a->emit,
                  "slurm: write DIR/sweep.slurm (a job array over the points still to run) instead of running")
      ->check(CLI::IsMember({"slurm"}));
  CLI::Option* ppt = cmd->add_option("--points-per-task", a->slurm.points_per_task,
                                     "--emit slurm: points each array task runs (default: the fewest that keep the "
                                     "array within 999 tasks, Slurm's default MaxArraySize being 1001)");
  cmd->add_option("--time", a->slurm.time, "--emit slurm: each task's time limit (#SBATCH --time), e.g. 2:00:00");
  cmd->add_option("--mem", a->slurm.mem, "--emit slurm: each task's memory (#SBATCH --mem), e.g. 4G");
  cmd->add_option("--partition", a->slurm.partition, "--emit slurm: the partition (#SBATCH --partition)");
  cmd->add_option("--sbatch", a->slurm.sbatch,
                  "--emit slurm: one more #SBATCH line, e.g. --sbatch=--account=NAME (repeatable)")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->allow_extra_args(false);
  cmd->add_flag("--quiet,-q", a->quiet, "No progress or summary");
  cmd->callback([a, cmd, ppt] {
    a->points_per_task_given = ppt->count() > 0;
    checkOptions(*a, *cmd);
    runSweep(*a);
  });
}

}  // namespace oit::cli
