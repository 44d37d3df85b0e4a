// Each pass's time in the report (issue 22, item 2): timing.phase_cycles
// gives a two-pass algorithm's passes one by one, derived by hand here for
// adaptive transparency on both engines.
#include <gtest/gtest.h>

#include <vector>

#include "oit_rop/RopTestUtil.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

class PhaseCyclesOn : public ::testing::TestWithParam<SimEngine> {};

// Adaptive (k = 8), N = 8 fragments to one pixel, submitted front to back, one
// partition, fixed 20-cycle shader, input 2/clock, every line a hit or a fast
// clear (the hit latency). As in PixelLockTimingOn (test_pixel_lock.cpp): the
// first fragment of a pass reaches the lock at 24 (shader 20 + early depth 4),
// enters the cache at 25, leaves it at 35 (hit 10) and releases at the end of
// its blend, 35 + A_0 with A = base 8 + compares x 1 + moves x 2; each later
// fragment reaches the lock long before its predecessor releases and holds it
// hit 10 + A_i from that release.
//  Pass 0 (build): fragment i finds i nodes, all in front: compares
//  min(p + 1, n) = i, moves n - p + 1 = 1 (ALGORITHMS.md): A_i = 10 + i.
//    pass 0 = 35 + 10 + sum_{i=1}^{N-1} (10 + 10 + i) = 45 + 20 (N - 1) + N (N - 1) / 2 = 213.
//  Pass 1 (composite), from pass 0's end: fragment i compares the i nodes in
//  front and stops at its own: i + 1 compares, 1 move (the accumulator):
//  A_i = 11 + i.
//    pass 1 = 35 + 11 + sum_{i=1}^{N-1} (10 + 11 + i) = 46 + 21 (N - 1) + N (N - 1) / 2 = 221.
// The resolve (one tile) is what is left of the frame.
TEST_P(PhaseCyclesOn, AdaptiveTwoPassesEachTakeTheirHandDerivedTime) {
  constexpr uint64_t N = 8;
  std::vector<Fragment> fs;
  for (unsigned i = 0; i < N; ++i) fs.push_back(model::testutil::frag(3, 3, 0.1f + 0.1f * i, 1, 0, 0, 0.5f));
  RopConfig cfg = smallConfig();
  cfg.partitions.count = 1;
  cfg.input.latency_model = LatencyModel::Fixed;
  cfg.input.latency_min = 20;
  cfg.sim.engine = GetParam();
  ASSERT_EQ(cfg.input.fragments_per_clock, 2.0);
  ASSERT_EQ(cfg.cache.hit_latency, 10u);
  ASSERT_EQ(cfg.alu.base_latency, 8u);
  ASSERT_EQ(cfg.alu.cycles_per_compare, 1u);
  ASSERT_EQ(cfg.alu.cycles_per_row_moved, 2u);
  model::AlgorithmParams p;
  p.layers = N;
  const auto r = runInChild([&] { return timed("adaptive", p, fs, 16, 16, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& ph = r.stats["timing"]["phase_cycles"];
  ASSERT_EQ(ph["transparent"].size(), 2u);
  EXPECT_EQ(ph["opaque"].get<uint64_t>(), 0u);
  EXPECT_EQ(ph["transparent"][0].get<uint64_t>(), 45 + 20 * (N - 1) + N * (N - 1) / 2);
  EXPECT_EQ(ph["transparent"][1].get<uint64_t>(), 46 + 21 * (N - 1) + N * (N - 1) / 2);
  const uint64_t cycles = r.stats["timing"]["cycles"];
  EXPECT_EQ(ph["opaque"].get<uint64_t>() + ph["transparent"][0].get<uint64_t>() +
                ph["transparent"][1].get<uint64_t>() + ph["resolve"].get<uint64_t>(),
            cycles);
  EXPECT_GT(ph["resolve"].get<uint64_t>(), 0u);
}

INSTANTIATE_TEST_SUITE_P(TimingRun, PhaseCyclesOn, ::testing::ValuesIn(kBothEngines), engineName);

}  // namespace
