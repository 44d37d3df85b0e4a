// DramBusGaps: the idle stretches of a channel's bus a later read may take
// (MEMORY.md, "scheduling"). Ticks here are plain numbers.
#include <gtest/gtest.h>

#include "oit_rop/memory/DramBusGaps.hpp"

namespace oit::rop {
namespace {

using Gap = DramBusGaps::Gap;
using Asker = DramBusGaps::Asker;

// One gap [100, 200), left at booked burst 10 by a request arriving at 50.
DramBusGaps oneGap(bool write_before = false, bool write_after = false) {
  DramBusGaps g;
  g.add({100, 200, 10, 50, write_before, write_after});
  return g;
}

TEST(DramBusGaps, WhoMayTakeAGap) {
  const DramBusGaps g = oneGap();
  size_t i = 99;
  // FR-FCFS, window 8: booked within 8 bursts of the gap (10 + 7) takes it ...
  EXPECT_EQ(g.find(Asker{60, 17, 8}, 120, 40, 0, 0, i), 120u);
  EXPECT_EQ(i, 0u);
  // ... 8 or more bursts later does not, unless it arrived before the gap's maker.
  EXPECT_EQ(g.find(Asker{60, 18, 8}, 120, 40, 0, 0, i), DramBusGaps::kNone);
  EXPECT_EQ(g.find(Asker{49, 500, 0}, 120, 40, 0, 0, i), 120u);  // FCFS, first come
  EXPECT_EQ(g.find(Asker{50, 11, 0}, 120, 40, 0, 0, i), DramBusGaps::kNone);  // FCFS, came with or after it
}

TEST(DramBusGaps, DataMustFitWholeWithTheTurnarounds) {
  size_t i = 0;
  const Asker any{0, 10, 1};
  EXPECT_EQ(oneGap().find(any, 90, 100, 0, 0, i), 100u);                // starts at the gap's begin
  EXPECT_EQ(oneGap().find(any, 90, 101, 0, 0, i), DramBusGaps::kNone);  // 1 tick too long
  EXPECT_EQ(oneGap().find(any, 170, 40, 0, 0, i), DramBusGaps::kNone);  // its data could start only at 170
  // After a write: tWTR + CL (17) from the gap's begin; before a write: tRTW (2) to its end.
  EXPECT_EQ(oneGap(true, false).find(any, 90, 83, 17, 2, i), 117u);
  EXPECT_EQ(oneGap(true, false).find(any, 90, 84, 17, 2, i), DramBusGaps::kNone);
  EXPECT_EQ(oneGap(false, true).find(any, 90, 98, 17, 2, i), 100u);
  EXPECT_EQ(oneGap(false, true).find(any, 90, 99, 17, 2, i), DramBusGaps::kNone);
}

// Taking [120, 140) of [100, 200) leaves [100, 120) and [140, 200), both now
// next to a read; a side shorter than min_len (one burst) is dropped.
TEST(DramBusGaps, TakingSplitsTheGap) {
  DramBusGaps g = oneGap(true, true);
  g.take(0, 120, 20, 4);
  ASSERT_EQ(g.size(), 2u);
  EXPECT_EQ(g[0].begin, 100u);
  EXPECT_EQ(g[0].end, 120u);
  EXPECT_TRUE(g[0].write_before);
  EXPECT_FALSE(g[0].write_after);
  EXPECT_EQ(g[1].begin, 140u);
  EXPECT_EQ(g[1].end, 200u);
  EXPECT_FALSE(g[1].write_before);
  EXPECT_TRUE(g[1].write_after);
  EXPECT_EQ(g[1].seq, 10u);  // the window still counts from the gap's maker
  EXPECT_EQ(g.latestEnd(), 200u);
  g.take(1, 143, 57, 4);  // leaves [140, 143): shorter than a burst
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g.latestEnd(), 120u);
}

TEST(DramBusGaps, KeepsTheNewestGaps) {
  DramBusGaps g;
  for (uint64_t k = 0; k < DramBusGaps::kMaxGaps + 3; ++k) g.add({k * 100, k * 100 + 50, k, k, false, false});
  ASSERT_EQ(g.size(), DramBusGaps::kMaxGaps);
  EXPECT_EQ(g[0].begin, 300u);  // the three oldest are forgotten
  size_t i = 0;
  EXPECT_EQ(g.find(Asker{0, 0, 0}, 0, 10, 0, 0, i), 300u);  // the earliest kept gap that fits
  EXPECT_EQ(i, 0u);
}

}  // namespace
}  // namespace oit::rop
