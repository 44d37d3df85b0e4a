// BlendAlu: rows per outcome, latency, format-scaled throughput, completion order.
#include <gtest/gtest.h>

#include <vector>

#include "oit_rop/stages/BlendAlu.hpp"

using namespace oit::rop;
using oit::model::InsertOutcome;

TEST(BlendAlu, RowsFollowTheOutcomeAndLazyMerge) {
  EXPECT_EQ(BlendAlu::rowsFor(InsertOutcome::Stored, 4, true), 1u);
  EXPECT_EQ(BlendAlu::rowsFor(InsertOutcome::Merged, 4, true), 4u);
  EXPECT_EQ(BlendAlu::rowsFor(InsertOutcome::Discarded, 4, true), 0u);
  EXPECT_EQ(BlendAlu::rowsFor(InsertOutcome::Stored, 4, false), 4u);  // every insert pays the merge
  EXPECT_EQ(BlendAlu::rowsFor(InsertOutcome::Merged, 0, true), 1u);   // accumulator layouts: one "row"
}

// The approximate engine tallies its visits and counts them at once:
// countMany(rows, drop, n) counts n blends (or drops), rows capped at rows_max;
// latencyOf(rows) is base + row x rows, capped the same way.
TEST(BlendAlu, CountManyAndLatencyOf) {
  AluConfig c;  // base 8, row 2
  BlendAlu many(c, 1.0, 4);
  many.countMany(3, false, 5);
  many.countMany(9, false, 2);  // capped at 4 rows
  many.countMany(0, true, 3);
  EXPECT_EQ(many.stats().blends, 7u);
  EXPECT_EQ(many.stats().rows, 5u * 3 + 2u * 4);
  EXPECT_EQ(many.stats().dropped, 3u);
  EXPECT_EQ(many.latencyOf(3), 14u);
  EXPECT_EQ(many.latencyOf(9), 16u);
  EXPECT_EQ(many.latencyOf(1), 10u);
  EXPECT_EQ(many.latencyOf(0), 8u);
}

TEST(BlendAlu, Fp32RateQuartersThroughputAndLatencyGrowsWithRows) {
  AluConfig c;  // 2 per clock, base 8, row 2, fp32 x0.25
  oit::model::StateLayout l{4, oit::model::StorageFormat::Fp32, 0, ""};
  EXPECT_DOUBLE_EQ(BlendAlu::formatRate(c, l), 0.25);
  BlendAlu alu(c, BlendAlu::formatRate(c, l), 4);
  EXPECT_EQ(alu.latency(4), 16u);
  std::vector<Cycle> issued_at;
  std::vector<std::pair<Cycle, uint32_t>> done;
  uint32_t next = 0;
  for (Cycle now = 0; now < 200; ++now) {
    alu.complete(now, [&](uint32_t t) { done.push_back({now, t}); });
    if (next < 10 && alu.slots(now) > 0) {
      alu.issue(now, next, next % 2 ? 4 : 0);
      issued_at.push_back(now);
      ++next;
    }
  }
  ASSERT_EQ(issued_at.size(), 10u);
  for (size_t i = 2; i < issued_at.size(); ++i) EXPECT_EQ(issued_at[i] - issued_at[i - 1], 2u);  // 0.5 per clock
  ASSERT_EQ(done.size(), 10u);
  for (size_t i = 0; i < done.size(); ++i) {
    const uint32_t t = done[i].second;
    EXPECT_EQ(done[i].first, issued_at[t] + (t % 2 ? 16u : 8u));
    if (i) {
      EXPECT_GE(done[i].first, done[i - 1].first);
    }
  }
  EXPECT_EQ(alu.stats().rows, 5u * 4u);
}
