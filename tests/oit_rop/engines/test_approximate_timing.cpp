// The approximate engine (sim.engine = approximate): its building blocks
// (StageTimeline, ReleaseTable) with exact values, and whole runs against the
// cycle engine: the same image and fragment counts always, timing and traffic
// within the tolerances DESIGN.md states.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <set>

#include "oit_rop/RopTestUtil.hpp"
#include "oit_rop/engines/ApproximateTiming.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

TEST(StageTimeline, AccountsGapsStallsAndBusyOnceEach) {
  StageCycles acc;
  StageTimeline t(10);
  t.add(acc, 12, 15, StageStatus::busy());                        // gap 10-12 starved, busy 12-15
  t.add(acc, 13, 20, StageStatus::stall(Stall::LockWait));        // 15-20 (13-15 already accounted)
  t.add(acc, 14, 18, StageStatus::busy());                        // inside accounted time: nothing
  t.add(acc, 25, 26, StageStatus::busy(), StageStatus::idle());  // gap 20-25 idle, busy 25-26
  t.close(acc, 30, StageStatus::idle());                          // 26-30 idle
  t.close(acc, 28, StageStatus::busy());                          // already there: nothing
  EXPECT_EQ(acc.busy, 3u + 1u);
  EXPECT_EQ(acc.stalls[size_t(Stall::LockWait)], 5u);
  EXPECT_EQ(acc.stalls[size_t(Stall::InputStarved)], 2u);
  EXPECT_EQ(acc.idle, 5u + 4u);
  EXPECT_EQ(acc.total(), 20u);  // exactly [10, 30)
  EXPECT_EQ(t.cursor(), 30u);
}

// addLeavingGap() + addGaps() account what add() with input-starved gaps does,
// on an account that already held cycles (the phase continues its stage's).
TEST(StageTimeline, GapsLeftForTheEndAccountAsAddDoes) {
  StageCycles a, b;
  a.busy = b.busy = 7;
  a.idle = b.idle = 3;
  StageTimeline ta(100), tb(100);
  const uint64_t total_at_start = b.total();
  uint64_t x = 4242;
  const auto next = [&x] { return x = x * 6364136223846793005ull + 1442695040888963407ull, x >> 33; };
  Cycle t = 100;
  for (int i = 0; i < 10000; ++i) {
    t += next() % 4;
    const Cycle from = t + next() % 20, to = from + next() % 30;  // overlapping, out of order, some empty
    const StageStatus s = next() % 3 == 0 ? StageStatus::stall(Stall(next() % kStallCount)) : StageStatus::busy();
    ta.add(a, from, to, s);
    tb.addLeavingGap(b, from, to, s);
    ASSERT_EQ(ta.cursor(), tb.cursor()) << "step " << i;
  }
  tb.addGaps(b, 100, total_at_start);
  ta.close(a, t + 100, StageStatus::idle());
  tb.close(b, t + 100, StageStatus::idle());
  EXPECT_EQ(a.busy, b.busy);
  EXPECT_EQ(a.idle, b.idle);
  for (size_t c = 0; c < kStallCount; ++c) EXPECT_EQ(a.stalls[c], b.stalls[c]) << "stall " << c;
  EXPECT_GT(a.stalls[size_t(Stall::InputStarved)], 0u);
}

TEST(ReleaseTable, UngroupedWaitsForEveryEarlierRelease) {
  ReleaseTable r(4, false);
  EXPECT_EQ(r.enterAfter(2, 7), 0u);
  r.released(2, 100);
  EXPECT_EQ(r.enterAfter(2, 7), 100u);  // the same owner too: owners do not matter
  r.released(2, 90);                    // an earlier release does not lower it
  EXPECT_EQ(r.enterAfter(2, 8), 100u);
  EXPECT_EQ(r.enterAfter(3, 8), 0u);  // other addresses are free
}

TEST(ReleaseTable, GroupedOwnerWaitsOnlyForTheOwnersBeforeIt) {
  ReleaseTable r(2, true);
  EXPECT_EQ(r.enterAfter(0, 1), 0u);
  r.released(0, 50);
  EXPECT_EQ(r.enterAfter(0, 1), 0u);  // owner 1 again: not behind its own fragment
  r.released(0, 60);
  EXPECT_EQ(r.enterAfter(0, 2), 60u);  // owner 2: behind both of owner 1
  r.released(0, 80);
  EXPECT_EQ(r.enterAfter(0, 2), 60u);
  EXPECT_EQ(r.enterAfter(0, 3), 80u);
}

// The in-order early-depth stage seen from visits in issue order: a fragment
// leaves no earlier than the latest leave of those that arrived before it.
TEST(InOrderBlockers, HoldsLaterArrivalsBehindTheLatestEarlierLeave) {
  InOrderBlockers b;
  EXPECT_TRUE(b.empty());
  EXPECT_EQ(b.heldUntil(100, 0), 0u);
  b.add(10, 200);  // arrived at 10, waited for its depth tile until 200
  EXPECT_EQ(b.heldUntil(9, 0), 0u);     // arrived before it: not held
  EXPECT_EQ(b.heldUntil(10, 0), 200u);  // the same cycle, visited later: behind it
  EXPECT_EQ(b.heldUntil(50, 0), 200u);
  b.add(30, 150);  // arrived later, left earlier: held by (10, 200) anyway, not kept
  EXPECT_EQ(b.size(), 1u);
  b.add(5, 120);  // arrived earlier (a shorter latency), left earlier: a step before it
  EXPECT_EQ(b.size(), 2u);
  EXPECT_EQ(b.heldUntil(7, 0), 120u);
  EXPECT_EQ(b.heldUntil(12, 0), 200u);
  b.add(20, 300);  // a later, longer wait
  EXPECT_EQ(b.heldUntil(15, 0), 200u);
  EXPECT_EQ(b.heldUntil(25, 0), 300u);
  b.add(3, 400);  // an earlier arrival leaving last holds everyone after it: the only step left
  EXPECT_EQ(b.size(), 1u);
  EXPECT_EQ(b.heldUntil(4, 0), 400u);
  EXPECT_EQ(b.heldUntil(2, 0), 0u);
  // Steps that left by the floor (no later visit arrives before it) are dropped.
  EXPECT_EQ(b.heldUntil(500, 400), 0u);
  EXPECT_TRUE(b.empty());
}

TEST(ReleaseCalendar, RetiresDueReleasesAndPopsTheEarliest) {
  ReleaseCalendar c;
  c.reset(100);  // cycles up to 100 retired
  c.push(105);
  c.push(103);
  c.push(105);
  c.push(100 + ReleaseCalendar::kWindow + 50);  // beyond the counts: the heap
  c.push(90);                                   // already due
  EXPECT_EQ(c.size(), 5u);
  EXPECT_EQ(c.popEarliest(), 100u);  // the due one: reported as the last retired cycle
  EXPECT_EQ(c.popEarliest(), 103u);
  EXPECT_EQ(c.size(), 3u);
  c.retire(104);  // nothing due at 104 (103 was popped)
  EXPECT_EQ(c.size(), 3u);
  c.retire(105);  // both 105s
  EXPECT_EQ(c.size(), 1u);
  EXPECT_EQ(c.popEarliest(), 100u + ReleaseCalendar::kWindow + 50);
  EXPECT_TRUE(c.empty());
  EXPECT_THROW(c.popEarliest(), std::logic_error);
}

// A ReleaseCalendar beside a multiset of the same releases, driven by a
// seeded LCG: the randomised tests below differ only in their mix of steps.
struct CalendarCheck {
  ReleaseCalendar c;
  std::multiset<Cycle> ref;
  Cycle now;
  uint64_t x;
  CalendarCheck(Cycle start, uint64_t seed) : now(start), x(seed) { c.reset(now); }
  uint64_t next() { return x = x * 6364136223846793005ull + 1442695040888963407ull, x >> 33; }
  void push(Cycle t) {
    c.push(t);
    ref.insert(t);
  }
  void retire() {
    c.retire(now);
    ref.erase(ref.begin(), ref.upper_bound(now));
  }
  Cycle popReference() {  // the reference's earliest, removed
    const Cycle t = *ref.begin();
    ref.erase(ref.begin());
    return t;
  }
};

TEST(ReleaseCalendar, MatchesASortedListAcrossWrapsAndJumps) {
  // A pseudo-random mix of pushes (0 to 3 windows ahead), retires (small
  // steps and jumps past the window) and pops, checked against a multiset.
  CalendarCheck k(7, 12345);
  for (int i = 0; i < 200000; ++i) {
    const uint64_t op = k.next() % 16;
    if (op < 8) {
      k.push(k.now + k.next() % (op < 6 ? 300 : 3 * ReleaseCalendar::kWindow));
    } else if (op < 13) {
      k.now += op == 12 && k.next() % 64 == 0 ? 2 * ReleaseCalendar::kWindow : k.next() % 5;
      k.retire();
    } else if (!k.ref.empty()) {
      const Cycle t = k.c.popEarliest();
      EXPECT_EQ(t, std::max(k.popReference(), k.now)) << "step " << i;  // a due entry reads as `now`
    }
    ASSERT_EQ(k.c.size(), k.ref.size()) << "step " << i;
  }
}

// The engine retires lazily: time moves on without retire(), and a full
// scoreboard drops (dropDue) or pops releases that are already due. Pops still
// come in release order, dropDue() takes exactly the earliest cycle's releases
// when they are due, and a late retire() drops exactly the entries due by then.
TEST(ReleaseCalendar, LazyRetireKeepsPopOrderAndCounts) {
  CalendarCheck k(3, 987654321);
  for (int i = 0; i < 200000; ++i) {
    const uint64_t op = k.next() % 16;
    if (op < 8) {
      k.push(k.now + 1 + k.next() % (op < 7 ? 400 : 2 * ReleaseCalendar::kWindow));  // always after now
    } else if (op < 11) {
      k.now += k.next() % 7;  // time moves; nothing retired
    } else if (op == 11) {
      k.retire();
    } else if (op == 12) {  // drop the earliest cycle's releases if due
      const bool due = !k.ref.empty() && *k.ref.begin() <= k.now;
      ASSERT_EQ(k.c.dropDue(k.now), due) << "step " << i;
      if (due) k.ref.erase(*k.ref.begin());
    } else if (!k.ref.empty()) {
      const Cycle t = k.c.popEarliest();
      EXPECT_EQ(t, k.popReference()) << "step " << i;  // due or not, the earliest
    }
    ASSERT_EQ(k.c.size(), k.ref.size()) << "step " << i;
  }
}

RopConfig approximate(RopConfig c = smallConfig()) {
  c.sim.engine = SimEngine::Approximate;
  return c;
}

uint64_t stagesTotal(const nlohmann::json& st) {
  uint64_t stalls = 0;
  for (const auto& [cause, v] : st["stalls"].items()) stalls += v.get<uint64_t>();
  return st["busy"].get<uint64_t>() + stalls + st["idle"].get<uint64_t>();
}

class ApproximateEveryAlgorithm : public ::testing::TestWithParam<std::string> {};

TEST_P(ApproximateEveryAlgorithm, ImageAndCountsAsFunctionalAndAccountsBalanced) {
  constexpr uint32_t W = 64, H = 64;
  const auto fs = smallScene(W, H, 6, 11);
  const model::AlgorithmParams p;
  const auto ref = model::testutil::render(GetParam(), p, fs, W, H);
  RopConfig off = approximate();
  off.skip.early_depth = off.skip.fast_clear = off.skip.lazy_merge = false;
  for (const RopConfig& cfg : {approximate(), off}) {
    const auto r = runInChild([&] { return timed(GetParam(), p, fs, W, H, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_TRUE(sameBits(r.image, ref.image)) << GetParam();
    EXPECT_EQ(r.counts.stored, ref.counts.stored);
    EXPECT_EQ(r.counts.merged, ref.counts.merged);
    EXPECT_EQ(r.counts.culled, ref.counts.culled);
    EXPECT_EQ(r.counts.pass_outcomes, ref.counts.pass_outcomes);
    EXPECT_TRUE(r.stats["fragments"]["outcomes_sum_to_in"].get<bool>());
    const uint64_t total = r.stats["timing"]["partition_cycles"];
    for (const auto& [name, st] : r.stats["timing"]["stages"].items()) EXPECT_EQ(stagesTotal(st), total) << name;
    // Every transparent fragment of every pass entered the lock once, unless culled early.
    const auto& f = r.stats["fragments"];
    const uint64_t transparent = f["in"].get<uint64_t>() - f["opaque"].get<uint64_t>();
    EXPECT_EQ(r.stats["lock"]["entries"].get<uint64_t>() + r.stats["skips"]["early_depth_culled"].get<uint64_t>(),
              transparent * f["pass_outcomes"].size());
  }
}

INSTANTIATE_TEST_SUITE_P(ApproximateTiming, ApproximateEveryAlgorithm, ::testing::ValuesIn(allAlgorithmNames()), paramName);

double rel(const nlohmann::json& a, const nlohmann::json& b) {
  const double x = a.get<double>(), y = b.get<double>();
  return y == 0 ? std::abs(x) : std::abs(x - y) / y;
}

// The measured agreement with the cycle engine (DESIGN.md's tolerance table).
TEST(ApproximateTiming, CloseToTheCycleEngine) {
  const MlabAgreementScene s;
  RopConfig cyc = smallConfig();
  cyc.cache.size_bytes = 32 * 1024;  // misses and DRAM traffic matter
  const auto c = runInChild([&] { return timed("mlab", s.p, s.fs, s.W, s.H, cyc); });
  const auto a = runInChild([&] { return timed("mlab", s.p, s.fs, s.W, s.H, approximate(cyc)); });
  ASSERT_TRUE(c.ok && a.ok) << c.error << a.error;
  EXPECT_TRUE(sameBits(a.image, c.image));
  const auto &cs = c.stats, &as = a.stats;
  // Measured: frame +0.14 % (3,497,650 against 3,492,697 cycles; +1.08 %
  // before issue 22 s5 booked the refused misses in time order). Misses and
  // blend-array bytes within 2 % as before. (Before the memory side worked in
  // the visit's frame, session 9: frame +9.3 %.)
  EXPECT_LT(rel(as["timing"]["cycles"], cs["timing"]["cycles"]), 0.03);
  EXPECT_LT(rel(as["cache"]["misses"], cs["cache"]["misses"]), 0.02);
  EXPECT_LT(rel(as["memory"]["dram_read_bytes"]["blend_arrays"], cs["memory"]["dram_read_bytes"]["blend_arrays"]), 0.02);
  // Lock conflicts: 2,863 against 5,948, and no tolerance is claimed for
  // them (DESIGN.md, "Lock conflicts"): the cycle engine's cache port is in
  // order, so on this DRAM-bound frame its fragments wait 5,233 cycles on
  // average between lock admission and the port (behind refused misses and
  // the fills ahead of them), in flight meanwhile; the approximate engine's
  // reach the port 22 cycles after it. A younger fragment of the pixel that
  // arrives meanwhile conflicts in the cycle engine only, so the approximate
  // engine counts no more. Where nothing waits at the port the two agree:
  // test_approximate_lock_conflicts.cpp.
  EXPECT_LE(as["lock"]["conflicts"].get<uint64_t>(), cs["lock"]["conflicts"].get<uint64_t>());
}

// Bound by depth-read latency: no HiZ (every fragment reads its depth tile),
// input at 3 fragments per clock, the scoreboard full most of the time. Booking
// the memory side at each fragment's own (future) time left holes in the DRAM
// schedule that requests booked later in visit order but earlier in time
// could not use: depth reads waited 4.5x longer and the frame took +87 % on
// the bench configuration (DESIGN.md). In the visit's frame they are close.
TEST(ApproximateTiming, CloseOnALatencyBoundConfiguration) {
  constexpr uint32_t W = 192, H = 128;
  const auto fs = smallScene(W, H, 24, 3);
  model::AlgorithmParams p;
  p.format = model::StorageFormat::Fp16;
  RopConfig cyc = smallConfig();
  cyc.early_depth.hierarchical = false;
  cyc.alu.blends_per_clock = 1;
  cyc.input.fragments_per_clock = 3;
  const auto c = runInChild([&] { return timed("wboit", p, fs, W, H, cyc); });
  const auto a = runInChild([&] { return timed("wboit", p, fs, W, H, approximate(cyc)); });
  ASSERT_TRUE(c.ok && a.ok) << c.error << a.error;
  EXPECT_TRUE(sameBits(a.image, c.image));
  // Measured: +0.36 % (16,086,210 against 16,028,501); +85 % before.
  EXPECT_LT(rel(a.stats["timing"]["cycles"], c.stats["timing"]["cycles"]), 0.05);
}

// Bound by the in-order early depth: opaque depth 0.9 everywhere but one
// pixel at 0.5 in eight tiles, so transparent fragments at 0.7 need a depth
// read there (the HiZ cannot decide) and nowhere else; no l2/l3, 100 ns of
// DRAM controller latency, a fast input and a large scoreboard: each read's
// head holds every fragment behind it (the old dgpu's case of DESIGN.md's
// agreement table, where the approximate engine was -31 % before it held
// them: InOrderBlockers).
TEST(ApproximateTiming, CloseWhenEarlyDepthWaitsInOrder) {
  using namespace model::testutil;
  constexpr uint32_t W = 128, H = 64;
  std::vector<Fragment> fs;
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const bool near = x % 8 == 0 && y % 8 == 0 && x / 8 < 4 && (y / 8 == 0 || y / 8 == 4);
      fs.push_back(frag(uint16_t(x), uint16_t(y), near ? 0.5f : 0.9f, 0.2f, 0.2f, 0.2f, 1.0f, kOpaqueDraw));
    }
  for (unsigned layer = 0; layer < 16; ++layer)
    for (uint32_t y = 0; y < H; ++y)
      for (uint32_t x = 0; x < W; ++x) fs.push_back(frag(uint16_t(x), uint16_t(y), 0.7f, 0.8f, 0.4f, 0.1f, 0.5f, kTranspDraw));
  model::AlgorithmParams p;
  p.layers = 2;
  RopConfig cyc = smallConfig();
  cyc.l2.size_bytes = cyc.l3.size_bytes = 0;
  cyc.partitions.count = 4;
  cyc.cache.size_bytes = 512 * 1024;
  cyc.dram.controller_ns = 100;
  cyc.input.fragments_per_clock = 8;
  cyc.alu.blends_per_clock = 16;
  cyc.lock.capacity = 2048;
  const auto c = runInChild([&] { return timed("mlab", p, fs, W, H, cyc); });
  const auto a = runInChild([&] { return timed("mlab", p, fs, W, H, approximate(cyc)); });
  ASSERT_TRUE(c.ok && a.ok) << c.error << a.error;
  EXPECT_TRUE(sameBits(a.image, c.image));
  // Two marked tiles of each partition share a slot of the 16-entry depth-tile
  // buffer (local tiles 0 and 16), so every layer reads both again: 128 reads.
  // Measured: 15,137 against 15,390 cycles (-1.6 %); without the in-order rule
  // 12,466 (-19.0 %).
  EXPECT_EQ(c.stats["depth"]["depth_tile_reads"].get<uint64_t>(), 128u);
  EXPECT_LT(rel(a.stats["timing"]["cycles"], c.stats["timing"]["cycles"]), 0.03);
}

TEST(ApproximateTiming, Deterministic) {
  constexpr uint32_t W = 64, H = 64;
  const auto fs = smallScene(W, H, 8, 5);
  const auto a = runInChild([&] { return timed("mlab", {}, fs, W, H, approximate()); });
  const auto b = runInChild([&] { return timed("mlab", {}, fs, W, H, approximate()); });
  ASSERT_TRUE(a.ok && b.ok) << a.error << b.error;
  EXPECT_EQ(a.stats, b.stats);
}

}  // namespace
