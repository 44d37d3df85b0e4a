// Building blocks: Fifo, TimingWheel, RateLimiter, per-stage cycle accounts.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "oit_rop/stages/PipelineQueues.hpp"
#include "oit_rop/TimingStats.hpp"

using namespace oit::rop;

TEST(PipelineQueues, FifoKeepsOrderAcrossGrowth) {
  Fifo<int> f(2);
  for (int i = 0; i < 5; ++i) f.push(i);
  f.pop();
  for (int i = 5; i < 40; ++i) f.push(i);
  for (int i = 1; i < 40; ++i) {
    ASSERT_EQ(f.front(), i);
    f.pop();
  }
  EXPECT_TRUE(f.empty());
}

// The approximate engine reads its input through a Cursor: pops are the
// cursor's own until setHead(); a new cursor sees what was pushed meanwhile,
// also after the ring grew (the old cursor's ring is then stale).
TEST(PipelineQueues, FifoCursorPopsLocallyUntilSetHead) {
  Fifo<int> f(4);
  for (int i = 0; i < 3; ++i) f.push(i);
  auto c = f.cursor();
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.front(), 0);
  EXPECT_EQ(c.at(2), 2);
  c.pop();
  c.pop();
  EXPECT_EQ(f.size(), 3u);  // the FIFO does not see the cursor's pops yet
  f.setHead(c);
  EXPECT_EQ(f.size(), 1u);
  EXPECT_EQ(f.front(), 2);
  for (int i = 3; i < 20; ++i) f.push(i);  // grows (capacity 4 -> 32)
  c = f.cursor();
  ASSERT_EQ(c.size(), 18u);
  for (int i = 2; i < 20; ++i) {
    ASSERT_FALSE(c.empty());
    EXPECT_EQ(c.front(), i);
    c.pop();
  }
  EXPECT_TRUE(c.empty());
  f.setHead(c);
  EXPECT_TRUE(f.empty());
}

TEST(PipelineQueues, TimingWheelDeliversAtTheDueCycle) {
  TimingWheel w(16);
  w.schedule(5, 1);
  w.schedule(3, 2);
  w.schedule(5, 3);
  EXPECT_EQ(w.nextDue(0), 3u);
  std::vector<std::pair<Cycle, uint32_t>> got;
  for (Cycle c = 0; c < 10; ++c) w.drain(c, [&](uint32_t t) { got.push_back({c, t}); });
  EXPECT_EQ(got, (std::vector<std::pair<Cycle, uint32_t>>{{3, 2}, {5, 1}, {5, 3}}));
  EXPECT_EQ(w.nextDue(9), kNever);
}

TEST(PipelineQueues, RateLimiterIsExactForFractionalRatesWhateverTheSkips) {
  RateLimiter r(0.25);
  unsigned taken = 0;
  for (Cycle c = 0; c < 100; ++c)
    while (r.available(c) > 0) r.take(), ++taken;
  EXPECT_EQ(taken, 25u);  // 1 at cycle 0 (full bucket) + one per 4 cycles
  // A quarter-rate limiter whose full bucket was spent at cycle `at`.
  const auto spentAt = [](Cycle at) {
    RateLimiter l(0.25);
    l.available(at);
    l.take();
    return l;
  };
  RateLimiter s = spentAt(0);
  EXPECT_EQ(s.nextAvailable(0), 4u);
  EXPECT_EQ(s.available(3), 0u);
  EXPECT_EQ(s.available(4), 1u);
  RateLimiter two(2.0);
  EXPECT_EQ(two.available(0), 2u);
  // Asked about an earlier cycle than before, it grants nothing new (the
  // unsigned cycle difference must not wrap into a full bucket).
  RateLimiter q = spentAt(10);
  EXPECT_EQ(q.available(9), 0u);
  EXPECT_EQ(q.available(13), 0u);
  EXPECT_EQ(q.available(14), 1u);
}

// Slow rates are kept to 2^-20 per clock: 0.001 and 0.01 per clock pass 1 +
// 1000 tokens in 10^6 and 10^5 cycles (with 1/256 units both were rounded up,
// to 3907 and 1172 tokens: 0.001 and 0.0001 per clock gave the same frame).
TEST(PipelineQueues, RateLimiterKeepsSlowRates) {
  for (const auto& [rate, cycles] : {std::pair{0.001, Cycle(1000000)}, std::pair{0.01, Cycle(100000)}}) {
    RateLimiter r(rate);
    unsigned taken = 0;
    for (Cycle c = 0; c < cycles; c = r.nextAvailable(c))
      while (r.available(c) > 0) r.take(), ++taken;
    // 1 at cycle 0 (full bucket) + one per 1/rate cycles, to 2^-20 per clock
    EXPECT_NEAR(double(taken), 1.0 + rate * double(cycles), 1.0) << rate;
  }
  // The fastest rate after a long idle span: capped credit, no overflow.
  RateLimiter fast(RateLimiter::kMaxPerClock);
  EXPECT_EQ(fast.available(0), 1024u);
  for (int i = 0; i < 1024; ++i) fast.take();
  EXPECT_EQ(fast.available(Cycle(1) << 40), 1024u);
  EXPECT_THROW(RateLimiter(0.0), std::invalid_argument);
  EXPECT_THROW(RateLimiter(1025.0), std::invalid_argument);
}

TEST(TimingStats, AccountsBalanceAndPad) {
  StageAccounts a;
  a[Stage::PixelLock].add(StageStatus::busy(), 10);
  a[Stage::PixelLock].add(StageStatus::stall(Stall::LockWait), 5);
  a[Stage::PixelLock].add(StageStatus::idle(), 5);
  EXPECT_THROW(a.checkBalanced(30), std::logic_error);
  a.padTo(30);
  EXPECT_NO_THROW(a.checkBalanced(30));
  EXPECT_EQ(a[Stage::PixelLock].stalls[size_t(Stall::LockWait)], 5u);
  EXPECT_EQ(a[Stage::PixelLock].idle, 15u);
  EXPECT_EQ(a[Stage::Resolve].idle, 30u);
  EXPECT_THROW(a.padTo(20), std::logic_error);
  EXPECT_STREQ(stallKey(Stall::ScoreboardFull), "scoreboard_full");
  EXPECT_STREQ(surfaceKey(oit::rop::Surface::BlendArrays), "blend_arrays");
}

// Stages ask their limiter only on cycles where something could pass;
// nextAvailable() must then count from the last available() call, giving the
// answer a limiter asked every cycle would give.
TEST(PipelineQueues, RateLimiterNextAvailableIsTheSameWhetherAskedEveryCycleOrNot) {
  for (double rate : {0.25, 0.3, 0.5, 1.0, 1.5, 2.0}) {
    RateLimiter lazy(rate), eager(rate);
    Cycle asked = 0;
    for (Cycle now = 0; now < 400; ++now) {
      eager.available(now);
      // The lazy one is asked only every 7th cycle (and takes then).
      if (now % 7 == 0) {
        asked = now;
        const unsigned a = lazy.available(now), b = eager.available(now);
        ASSERT_EQ(a, b) << "rate " << rate << " cycle " << now;
        if (a > 0) lazy.take(), eager.take();
      }
      ASSERT_EQ(lazy.nextAvailable(now), eager.nextAvailable(now)) << "rate " << rate << " cycle " << now
                                                                    << " (last asked " << asked << ")";
    }
  }
  RateLimiter r(0.25);
  r.available(10);
  r.take();                                // credit 0 at cycle 10
  EXPECT_EQ(r.nextAvailable(10), 14u);     // one more token after 4 cycles
  EXPECT_EQ(r.nextAvailable(12), 14u);     // the same when asked later, without available(12)
  EXPECT_EQ(r.nextAvailable(20), 21u);     // already there: the next cycle
}
