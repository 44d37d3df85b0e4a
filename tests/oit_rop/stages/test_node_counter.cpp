// NodeCounter: the A-buffer's one node counter for the whole GPU.
#include <gtest/gtest.h>

#include <vector>

#include "oit_rop/stages/NodeCounter.hpp"

using namespace oit::rop;

// 1 atomic per clock, latency 100: N partitions each asking for M increments
// at cycle 0 are served one per cycle, N x M of them in cycles 0 .. NM - 1:
// the last returns at NM - 1 + 100, and the waits sum to 0 + 1 + ... + (NM - 1).
TEST(NodeCounter, PartitionsHammeringTheCounterShareItsRate) {
  for (unsigned n : {1u, 2u, 4u}) {
    NodeCounter c(1.0, 100);
    constexpr unsigned M = 50;
    Cycle last = 0;
    for (unsigned i = 0; i < M; ++i)
      for (unsigned p = 0; p < n; ++p) last = std::max(last, c.grant(0));
    EXPECT_EQ(last, Cycle(n * M - 1 + 100)) << n;
    EXPECT_EQ(c.atomics(), uint64_t(n) * M);
    EXPECT_EQ(c.waitCycles(), uint64_t(n * M) * (n * M - 1) / 2) << n;
  }
}

// Fractional rates: 0.25 per clock serves one every 4 cycles; 2 per clock two per cycle.
TEST(NodeCounter, FractionalAndWideRates) {
  NodeCounter quarter(0.25, 0);
  std::vector<Cycle> g;
  for (int i = 0; i < 4; ++i) g.push_back(quarter.grant(0));
  EXPECT_EQ(g, (std::vector<Cycle>{3, 7, 11, 15}));  // each needs 4 cycles of capacity
  NodeCounter two(2.0, 0);
  EXPECT_EQ(two.grant(10), 10u);
  EXPECT_EQ(two.grant(10), 10u);
  EXPECT_EQ(two.grant(10), 11u);
}

// A partition a quantum behind books the cycles the others left free: its
// request at cycle 5 is served at 5 although cycles 100..199 are booked.
TEST(NodeCounter, ALaterCallForAnEarlierCycleFillsTheGap) {
  NodeCounter c(1.0, 0);
  for (int i = 0; i < 100; ++i) c.grant(100);
  EXPECT_EQ(c.grant(5), 5u);
  EXPECT_EQ(c.grant(150), 200u);  // 100..199 taken
}

// Partitions a quantum of 100,000 apart: the calendar keeps the shared
// levels' lookback (2 x 100,000 + 4,096 = 204,096 cycles behind the latest
// request; a ring of 524,288 cycles, half of it behind the latest), so a
// partition behind is served at its own cycle. 1 atomic per clock, latency 10:
// the partition ahead takes cycle 100,000 (back at 100,010); the one behind
// asks at 10 and is served at 10, back at 20. Before, the window was 16,384
// cycles whatever the quantum: the first request retired everything before
// 100,000 - 8,192 = 91,808, and the one behind was served there (back at
// 91,818), in the other's future. With a small quantum (200, the default
// until session 22: a lookback of 4,496; the default 16 even less) the window
// stays 16,384, as before.
TEST(NodeCounter, APartitionAQuantumBehindIsServedAtItsOwnCycle) {
  NodeCounter c(1.0, 10, 2 * 100000 + 4096);
  EXPECT_EQ(c.grant(100000), 100010u);
  EXPECT_EQ(c.grant(10), 20u);
  EXPECT_EQ(c.waitCycles(), 0u);
  NodeCounter small_window(1.0, 10, 2 * 200 + 4096);  // the window's floor: 8,192 behind
  EXPECT_EQ(small_window.grant(100000), 100010u);
  EXPECT_EQ(small_window.grant(10), 91818u);
}
