// Timing runs in child processes (oit_rop/ChildRuns.hpp): results come back
// whole and in job order, a failing or dying child is named, and
// runTimingSeeds runs one seed per child.
#include <gtest/gtest.h>

#include <csignal>
#include <unistd.h>

#include "oit_rop/RopTestUtil.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

// A result without a simulation: what the pipe must carry back.
TimingResult fake(unsigned i) {
  TimingResult r;
  r.image = model::Image(3, 2, {0.25f * float(i), 0.5f, 1.0f});
  r.image.pixels[4] = {1e-30f, -0.0f, 3.0e38f};
  r.stats = {{"job", i}, {"text", std::string(100000, 'x')}};  // larger than a pipe's buffer
  r.counts.fragments_in = 10 + i;
  r.counts.stored = 7;
  r.counts.pass_outcomes = {{1, 2, 3}, {4, 5, 6}};
  r.counts.source_passes = 2;
  r.wall_seconds = 0.5 * i;
  r.pool_bytes = 123456789012ull;
  return r;
}

std::string errorOf(const std::vector<TimingJob>& jobs, ChildRunOptions o = {}) {
  try {
    runTimingInChildren(jobs, o);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(ChildRuns, ResultsComeBackWholeAndInJobOrder) {
  std::vector<TimingJob> jobs;
  for (unsigned i = 0; i < 5; ++i)
    jobs.push_back([i](const auto& progress) {
      progress(0.5, "half");
      if (i % 2 == 0) usleep(20000);  // finish out of order
      return fake(i);
    });
  std::vector<double> seen;
  ChildRunOptions o;
  o.parallel = 3;
  o.progress = [&](double f) { seen.push_back(f); };
  const std::vector<TimingResult> r = runTimingInChildren(jobs, o);
  ASSERT_EQ(r.size(), 5u);
  for (unsigned i = 0; i < 5; ++i) {
    const TimingResult want = fake(i);
    EXPECT_EQ(r[i].stats, want.stats);
    EXPECT_EQ(r[i].image.width, 3u);
    EXPECT_EQ(r[i].image.pixels, want.image.pixels);
    EXPECT_EQ(r[i].counts.fragments_in, want.counts.fragments_in);
    EXPECT_EQ(r[i].counts.stored, 7u);
    EXPECT_EQ(r[i].counts.pass_outcomes, want.counts.pass_outcomes);
    EXPECT_EQ(r[i].counts.source_passes, 2u);
    EXPECT_EQ(r[i].wall_seconds, want.wall_seconds);
    EXPECT_EQ(r[i].pool_bytes, want.pool_bytes);
  }
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back(), 1.0);
  for (size_t i = 1; i < seen.size(); ++i) EXPECT_GE(seen[i], seen[i - 1]);
}

TEST(ChildRuns, AFailingOrDyingChildIsNamed) {
  const TimingJob ok = [](const auto&) { return fake(0); };
  const TimingJob throws = [](const auto&) -> TimingResult { throw std::invalid_argument("bad trace: record 3"); };
  const TimingJob exits = [](const auto&) -> TimingResult { _exit(7); };
  const TimingJob killed = [](const auto&) -> TimingResult {
    std::raise(SIGKILL);
    return {};
  };
  EXPECT_EQ(errorOf({ok, throws}), "job 1: bad trace: record 3");
  EXPECT_EQ(errorOf({throws}), "bad trace: record 3");  // one job: its own message
  EXPECT_EQ(errorOf({exits, ok}), "job 0: the child process exited with status 7 without a result");
  EXPECT_EQ(errorOf({ok, ok, killed}), "job 2: the child process was killed by signal 9");
  ChildRunOptions named;
  named.parallel = 2;
  named.name = [](size_t i) { return "seed " + std::to_string(i); };
  EXPECT_EQ(errorOf({ok, throws}, named), "seed 1: bad trace: record 3");
}

// Seeds input.seed, +1, +2: an ordered ROP's image is the same for every seed
// (the functional one); the timing is each seed's own (as a single run).
TEST(ChildRuns, SeedsRunOnePerChild) {
  const auto fs = smallScene(32, 32, 6, 21);
  SeedRunsRequest rq;
  rq.cfg = smallConfig();
  rq.cfg.input.seed = 40;
  rq.seeds = 3;
  rq.parallel = 2;
  rq.open_trace = [&] { return std::make_unique<model::MemorySource>(model::testutil::header(32, 32), fs, 333); };
  rq.make_algorithm = [] { return model::makeAlgorithm("mlab", {}); };
  const std::vector<TimingResult> r = runTimingSeeds(rq);
  ASSERT_EQ(r.size(), 3u);
  const model::Image ref = model::testutil::render("mlab", {}, fs, 32, 32).image;
  for (unsigned i = 0; i < 3; ++i) {
    EXPECT_EQ(r[i].image.pixels, ref.pixels);
    RopConfig one = rq.cfg;
    one.input.seed = 40 + i;
    const ChildRun single = runInChild([&] { return timed("mlab", {}, fs, 32, 32, one); });
    ASSERT_TRUE(single.ok) << single.error;
    EXPECT_EQ(r[i].stats["timing"], single.stats["timing"]) << i;
  }
  EXPECT_NE(r[0].stats["timing"]["cycles"], r[1].stats["timing"]["cycles"]);  // the seeds differ
  rq.seeds = 0;
  EXPECT_THROW(runTimingSeeds(rq), std::invalid_argument);
}

}  // namespace
