// DramWriteQueue: posted writes wait, drain in batches between the
// watermarks, and hold their entries until their data is on the bus
// (MEMORY.md, "write queue"). Ticks here are plain numbers.
#include <gtest/gtest.h>

#include <vector>

#include "oit_rop/memory/DramWriteQueue.hpp"

namespace oit::rop {
namespace {

using WriteRun = DramWriteQueue::Run;

std::vector<WriteRun> batchOf(DramWriteQueue& q, bool all) { return q.takeBatch(all); }

// Capacity 32, high 20, low 8. Five runs of 4 bursts: A (bank 0, row 5),
// B (1, 7), C (0, 5), D (2, 9), E (1, 7) -> 20 waiting: the high watermark.
// The batch takes the oldest row (0, 5): A and C merged into one run of 8
// (one activate), 12 left > 8; then row (1, 7): B (4 left would be <= 8 after
// B, so E stays): 8 left. D and E wait.
TEST(DramWriteQueue, DrainsWholeRunsOfTheOldestRowsDownToTheLowWatermark) {
  DramWriteQueue q(32, 20, 8);
  q.add({0, 5, 4, 10});
  q.add({1, 7, 4, 11});
  q.add({0, 5, 4, 12});
  q.add({2, 9, 4, 13});
  EXPECT_FALSE(q.atHighWatermark());
  q.add({1, 7, 4, 14});
  EXPECT_TRUE(q.atHighWatermark());
  EXPECT_EQ(q.pendingBursts(), 20u);
  const std::vector<WriteRun> b = batchOf(q, false);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b[0].bank, 0u);
  EXPECT_EQ(b[0].row, 5u);
  EXPECT_EQ(b[0].bursts, 8u);
  EXPECT_EQ(b[0].accepted, 12u);  // the later of A's and C's: not written before C arrived
  EXPECT_EQ(b[1].bank, 1u);
  EXPECT_EQ(b[1].bursts, 4u);
  EXPECT_EQ(b[1].accepted, 11u);
  EXPECT_EQ(q.pendingBursts(), 8u);
  // All: the rest, oldest row first (D's, then E's).
  const std::vector<WriteRun> rest = batchOf(q, true);
  ASSERT_EQ(rest.size(), 2u);
  EXPECT_EQ(rest[0].row, 9u);
  EXPECT_EQ(rest[1].row, 7u);
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.pendingBursts(), 0u);
}

// An entry is held until its data is on the bus: with 6 of 8 entries drained
// but not yet written (data ends at tick 100), a run of 4 finds room at 100.
TEST(DramWriteQueue, ARunWaitsForRoomUntilDrainedDataIsOnTheBus) {
  DramWriteQueue q(8, 8, 0);
  q.add({0, 0, 6, 0});
  ASSERT_EQ(batchOf(q, true).size(), 1u);
  q.drained(100, 6);
  EXPECT_EQ(q.roomAt(50, 2), 50u);   // 6 + 2 <= 8
  EXPECT_EQ(q.roomAt(50, 4), 100u);  // 6 + 4 > 8: when the drained data ended
  EXPECT_EQ(q.roomAt(150, 8), 150u);  // nothing in flight any more
  // Waiting bursts count too: 5 wait, 3 in flight until 200, 2 until 300.
  q.add({0, 0, 5, 150});
  q.drained(200, 3);
  q.drained(300, 2);
  EXPECT_EQ(q.roomAt(160, 1), 200u);  // 5 + 5 + 1 > 8: the first 3 must be written
  EXPECT_EQ(q.roomAt(160, 3), 300u);  // 5 + 3 = 8: every drained entry must be free
  // A run larger than the queue waits until nothing drained is in flight.
  EXPECT_EQ(q.roomAt(160, 9), 300u);
  EXPECT_TRUE(q.wouldOverflow(4));  // 5 + 4 > 8: the controller drains first
  EXPECT_FALSE(q.wouldOverflow(3));
}

}  // namespace
}  // namespace oit::rop
