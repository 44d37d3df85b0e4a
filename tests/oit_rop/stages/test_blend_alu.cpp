// BlendAlu: latency from the insert's work, lazy merge, format-scaled
// throughput, completion order, a late start (the A-buffer's atomic).
#include <gtest/gtest.h>

#include <vector>

#include "oit_rop/stages/BlendAlu.hpp"

using namespace oit::rop;
using oit::model::InsertOutcome;
using oit::model::InsertWork;

// latency = base + cycles_per_compare x compares + cycles_per_row_moved x moves.
TEST(BlendAlu, LatencyIsTheInsertsWork) {
  AluConfig c;  // base 8, 1 per compare, 2 per row moved
  BlendAlu alu(c, 1.0);
  EXPECT_EQ(alu.latency({0, 0}), 8u);
  EXPECT_EQ(alu.latency({0, 1}), 10u);  // an accumulator: 8 + 2
  EXPECT_EQ(alu.latency({3, 2}), 15u);  // MLAB k=4, slot 2: compares rows 0..2, rewrites rows 2..3
  c.cycles_per_compare = 5;
  c.cycles_per_row_moved = 7;
  BlendAlu other(c, 1.0);
  EXPECT_EQ(other.latency({4, 3}), 8u + 5 * 4 + 7 * 3);
  alu.count({3, 2}, false);
  alu.count({1, 0}, false);
  alu.count({9, 9}, true);  // a drop does no work
  EXPECT_EQ(alu.stats().blends, 2u);
  EXPECT_EQ(alu.stats().dropped, 1u);
  EXPECT_EQ(alu.stats().compares, 4u);
  EXPECT_EQ(alu.stats().moves, 2u);
}

// Without lazy merging a Stored insert pays the merge: at least the array's rows moved.
TEST(BlendAlu, ChargedWorkWithoutLazyMerge) {
  const InsertWork w{2, 1};
  EXPECT_EQ(BlendAlu::chargedWork(w, InsertOutcome::Stored, 4, true).moves, 1u);
  EXPECT_EQ(BlendAlu::chargedWork(w, InsertOutcome::Stored, 4, false).moves, 4u);
  EXPECT_EQ(BlendAlu::chargedWork(w, InsertOutcome::Merged, 4, false).moves, 1u);  // its own work
  EXPECT_EQ(BlendAlu::chargedWork(w, InsertOutcome::Stored, 0, false).moves, 1u);  // accumulators: one row
  EXPECT_EQ(BlendAlu::chargedWork(w, InsertOutcome::Stored, 4, false).compares, 2u);
}

TEST(BlendAlu, Fp32RateQuartersThroughputAndLatencyFollowsWork) {
  AluConfig c;  // 2 per clock, base 8, fp32 x0.25
  oit::model::StateLayout l{4, oit::model::StorageFormat::Fp32, 0, ""};
  EXPECT_DOUBLE_EQ(BlendAlu::formatRate(c, l), 0.25);
  BlendAlu alu(c, BlendAlu::formatRate(c, l));
  std::vector<Cycle> issued_at;
  std::vector<std::pair<Cycle, uint32_t>> done;
  uint32_t next = 0;
  for (Cycle now = 0; now < 200; ++now) {
    alu.complete(now, [&](uint32_t t) { done.push_back({now, t}); });
    if (next < 10 && alu.slots(now) > 0) {
      alu.issue(now, next, next % 2 ? InsertWork{0, 4} : InsertWork{0, 0});
      issued_at.push_back(now);
      ++next;
    }
  }
  ASSERT_EQ(issued_at.size(), 10u);
  for (size_t i = 2; i < issued_at.size(); ++i) EXPECT_EQ(issued_at[i] - issued_at[i - 1], 2u);  // 0.5 per clock
  ASSERT_EQ(done.size(), 10u);
  for (size_t i = 0; i < done.size(); ++i) {
    const uint32_t t = done[i].second;
    EXPECT_EQ(done[i].first, issued_at[t] + (t % 2 ? 16u : 8u));  // 8 + 2 x 4 moved rows
    if (i) {
      EXPECT_GE(done[i].first, done[i - 1].first);
    }
  }
  EXPECT_EQ(alu.stats().moves, 5u * 4u);
}

// A blend whose work starts later (it waited for the node counter) finishes
// at start + latency; blends finishing in the same cycle complete in issue order.
TEST(BlendAlu, LateStartAndTiesInIssueOrder) {
  AluConfig c;
  c.blends_per_clock = 4;
  BlendAlu alu(c, 1.0);
  ASSERT_GE(alu.slots(0), 3u);
  alu.issue(0, 7, {0, 1}, false, 30);  // done 30 + 10
  alu.issue(0, 8, {0, 1});             // done 10
  alu.issue(0, 9, {0, 1});             // done 10, after 8
  std::vector<std::pair<Cycle, uint32_t>> done;
  for (Cycle now = 0; now <= 40; ++now) alu.complete(now, [&](uint32_t t) { done.push_back({now, t}); });
  ASSERT_EQ(done.size(), 3u);
  EXPECT_EQ(done[0], (std::pair<Cycle, uint32_t>{10, 8}));
  EXPECT_EQ(done[1], (std::pair<Cycle, uint32_t>{10, 9}));
  EXPECT_EQ(done[2], (std::pair<Cycle, uint32_t>{40, 7}));
}
