// The Slurm job array of a sweep (reports/SlurmScript.hpp): chunking into
// tasks, Slurm's time and memory syntax, options passed through.
#include <gtest/gtest.h>

#include "reports/SlurmScript.hpp"

namespace oit::sweep {
namespace {

Plan planOf(size_t points) {
  Plan p;
  p.spec = "/s/spec.json";
  p.out = "/w/sweep";
  p.executable = "/usr/bin/oitsim";
  for (size_t i = 0; i < points; ++i) p.points.push_back({"id" + std::to_string(i), "t", ojson::object(), {"run"}});
  return p;
}

// 5 points at 2 per task: tasks {0 1}, {2 3}, {4}: an array 0-2.
TEST(SlurmScript, PointsAreChunkedIntoTasks) {
  const Plan plan = planOf(5);
  SlurmOptions o;
  o.points_per_task = 2;
  const SlurmJob job = makeSlurmJob(plan, {0, 1, 2, 3, 4}, o);
  EXPECT_EQ(job.task_count, 3u);
  EXPECT_EQ(job.points_per_task, 2u);
  EXPECT_EQ(job.tasks, "0 1\n2 3\n4\n");
  EXPECT_NE(job.script.find("#SBATCH --array=0-2\n"), std::string::npos) << job.script;
  EXPECT_NE(job.script.find("#SBATCH --output=/w/sweep/slurm-%A_%a.log\n"), std::string::npos);
  EXPECT_NE(job.script.find("sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" /w/sweep/slurm-tasks.txt"), std::string::npos);
  EXPECT_EQ(job.script.find("--time"), std::string::npos) << "no --time given: none written";
  // Only the points still to run (a resumed sweep): their own line numbers.
  const SlurmJob rest = makeSlurmJob(plan, {1, 4}, o);
  EXPECT_EQ(rest.tasks, "1 4\n");
  EXPECT_NE(rest.script.find("#SBATCH --array=0-0\n"), std::string::npos);
}

// Slurm's default MaxArraySize is 1001: by default an array has at most 999
// tasks, so 999 points run one per task and 1,100 two per task (550 tasks).
TEST(SlurmScript, DefaultChunkingKeepsTheArrayUnder1000Tasks) {
  EXPECT_EQ(defaultPointsPerTask(1), 1u);
  EXPECT_EQ(defaultPointsPerTask(999), 1u);
  EXPECT_EQ(defaultPointsPerTask(1000), 2u);
  EXPECT_EQ(defaultPointsPerTask(1100), 2u);
  EXPECT_EQ(defaultPointsPerTask(99900), 100u);
  EXPECT_EQ(defaultPointsPerTask(99901), 101u);
  const Plan plan = planOf(1100);
  std::vector<size_t> all(1100);
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  const SlurmJob job = makeSlurmJob(plan, all, {});
  EXPECT_EQ(job.task_count, 550u);
  EXPECT_NE(job.script.find("#SBATCH --array=0-549\n"), std::string::npos);
}

TEST(SlurmScript, SiteOptionsArePassedThrough) {
  SlurmOptions o;
  o.time = "1-02:00:00";
  o.mem = "4G";
  o.partition = "cpu";
  o.sbatch = {"--account=arch", "--qos=low"};
  checkSlurmOptions(o, false);
  const SlurmJob job = makeSlurmJob(planOf(2), {0, 1}, o);
  EXPECT_NE(job.script.find("#SBATCH --time=1-02:00:00\n#SBATCH --mem=4G\n#SBATCH --partition=cpu\n"
                            "#SBATCH --account=arch\n#SBATCH --qos=low\n"),
            std::string::npos)
      << job.script;
}

TEST(SlurmScript, TimeAndMemoryFollowSbatchSyntax) {
  for (const char* t : {"30", "30:00", "2:00:00", "1-0", "1-12:30", "1-12:30:15", "0:59"})
    EXPECT_TRUE(isSlurmTime(t)) << t;
  for (const char* t : {"", "1h", "2:00:00:00", "-5", "1.5", "1-", "12:345", "one"}) EXPECT_FALSE(isSlurmTime(t)) << t;
  for (const char* m : {"2G", "512M", "4096", "1T", "100K"}) EXPECT_TRUE(isSlurmMemory(m)) << m;
  for (const char* m : {"", "0", "2GB", "1.5G", "G", "-1G", "2g"}) EXPECT_FALSE(isSlurmMemory(m)) << m;
}

TEST(SlurmScript, BadOptionsNameTheOption) {
  auto error = [](SlurmOptions o, bool ppt_given) {
    try {
      checkSlurmOptions(o, ppt_given);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  SlurmOptions o;
  EXPECT_EQ(error(o, true), "--points-per-task 0: expected a positive number of points per Slurm array task");
  o.time = "2h";
  EXPECT_EQ(error(o, false).rfind("--time 2h: not a Slurm time limit (expected minutes, MM:SS, HH:MM:SS", 0), 0u);
  o.time.clear();
  o.mem = "2GB";
  EXPECT_EQ(error(o, false).rfind("--mem 2GB: not a Slurm memory size", 0), 0u);
  o.mem.clear();
  o.partition = "a b";
  EXPECT_EQ(error(o, false).rfind("--partition a b: expected a partition name", 0), 0u);
  o.partition.clear();
  o.sbatch = {"account=x"};
  EXPECT_EQ(error(o, false).rfind("--sbatch 'account=x': expected one sbatch option", 0), 0u);
}

}  // namespace
}  // namespace oit::sweep
