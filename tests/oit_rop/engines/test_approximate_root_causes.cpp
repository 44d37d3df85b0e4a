// The approximate engine's root causes against the cycle engine's where a
// wait is a fixed latency, not a resource (oit_rop/DESIGN.md "Root causes",
// the approximate engine): the A-buffer's node-counter atomic.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "oit_rop/RopTestUtil.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

class AbufferAtomicCause : public ::testing::TestWithParam<SimEngine> {};

// 64x32 pixels x 8 layers of A-buffer nodes (16,384 stored; the pool's 16
// nodes per pixel hold them all) on one partition: 4 fragments per clock into
// 1 blend per clock at the fp32 rate 0.25 (the A-buffer's per-pixel state, its
// 4-byte head, is an fp32 word: BlendAlu::formatRate), so the blends queue for
// the ALU and the transparent pass takes at least 16,384 / 0.25 = 65,536
// cycles. The node counter serves 4 atomics per clock against 0.25 asked: no
// atomic waits for it. Each atomic's latency (400 cycles here) runs while the
// ALU works on the blends ahead of it (one every 4 cycles, each 10 long: base
// 8 + one node written x 2), so it holds the pass only before the first blend
// works: every blend in flight waits for its atomic for 400 cycles, then never
// again. So the pass is the ALU's and atomic_wait gets at most 400 cycles
// (cycle engine: exactly 400; approximate: 1). Until session 21 the
// approximate engine added every atomic's whole latency to the delays a full
// scoreboard's span is shared out by, 400 a fragment beside its ALU
// queueing: atomic_wait 32,864 cycles (22.7 % of the frame). (With
// bench_timing's --algo abuffer, two partitions at 0.5 blends per clock and
// the default 100-cycle latency, 15.6 % against the cycle engine's 0.0 %.)
TEST_P(AbufferAtomicCause, TheAtomicsLatencyUnderAnAluBoundPassIsNotAWait) {
  const std::vector<Fragment> fs = layerSweeps(64, 32, 8, 1.0f / 16.0f);
  RopConfig c = smallConfig();
  c.sim.engine = GetParam();
  c.partitions.count = 1;
  c.input.latency_model = LatencyModel::Fixed;
  c.input.latency_min = 40;
  c.input.fragments_per_clock = 4.0;
  c.alu.blends_per_clock = 1;
  c.abuffer.atomics_per_clock = 4.0;
  c.abuffer.atomic_latency = 400;
  ASSERT_EQ(c.alu.fp32_rate, 0.25);
  ASSERT_EQ(c.alu.base_latency + c.alu.cycles_per_row_moved, 10u);
  model::AlgorithmParams p;
  p.format = model::StorageFormat::Rgba8T8Z32;
  const auto r = runInChild([&] { return timed("abuffer", p, fs, 64, 32, c); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& t = r.stats["timing"];
  EXPECT_EQ(r.stats["alu"]["node_counter"]["atomics"].get<uint64_t>(), 16384u);
  EXPECT_EQ(r.stats["alu"]["node_counter"]["wait_cycles"].get<uint64_t>(), 0u);
  EXPECT_GE(t["phase_cycles"]["transparent"][0].get<uint64_t>(), 65536u);
  EXPECT_LE(t["root_cause_cycles"]["atomic_wait"].get<uint64_t>(), 400u) << t["root_cause_cycles"].dump();
  EXPECT_EQ(t["bound_by"]["resource"].get<std::string>(), "alu") << t["root_cause_cycles"].dump();
}

INSTANTIATE_TEST_SUITE_P(RootCauses, AbufferAtomicCause, ::testing::ValuesIn(kBothEngines), engineName);

}  // namespace
