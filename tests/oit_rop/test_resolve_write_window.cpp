// The resolve's posted colour writes (oit_rop/DESIGN.md "Stages", Resolve;
// "Root causes"): they may run 1024 cycles ahead of the resolve, and the
// frame ends when the last one is done. With shared levels a write is done
// when its bytes crossed the l2's port, so a resolve held by that window, and
// the frame's tail of writes in flight, wait for the l2 port: charged `l2`.
// (Until issue 22 s5 both were charged `dram_bandwidth` whatever held the
// writes: the 10.6 M-fragment hair A-buffer point showed 21 % dram_bandwidth
// with the DRAM bus idle, reports/repro/papers/README.md.)
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "oit_rop/RopTestUtil.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

class ResolveWriteWindow : public ::testing::TestWithParam<SimEngine> {};

uint64_t cause(const ChildRun& r, const char* key) {
  return r.stats["timing"]["root_cause_cycles"][key].get<uint64_t>();
}

// One partition, a fixed shader latency, 4 blends per clock.
RopConfig onePartition(SimEngine engine) {
  RopConfig c = smallConfig();
  c.sim.engine = engine;
  c.partitions.count = 1;
  c.input.latency_model = LatencyModel::Fixed;
  c.input.latency_min = 40;
  c.alu.blends_per_clock = 4;
  return c;
}

// 16x16 pixels, one layer of alpha blending in rgba8 (4 B per pixel).
ChildRun alphaFrame(const RopConfig& c) {
  model::AlgorithmParams p;
  p.format = model::StorageFormat::Rgba8T8Z32;
  const auto fs = layerSweeps(16, 16, 1, 1.0f / 1024.0f);
  return runInChild([&] { return timed("alpha", p, fs, 16, 16, c); });
}

// 16x16 pixels, one layer of alpha blending (rgba8: 4 B per pixel), one
// partition, 8x8 tiles: 4 tiles. The arrays (1 KiB) stay in the 64 KiB ROP
// cache, so the l2 sees only the resolve's colour writes, 256 B per tile, over
// a port of 0.25 B/clock: 1024 cycles each. A tile's resolve computes 64 px at
// 4 blends/clock = 16 cycles. With t0 the end of tile 0's compute:
//  - tile 0 writes at t0: the port moves it over [t0, t0 + 1024);
//  - tile 1 starts at t0 (its write would be done at t0 + 1024, not past
//    t0 + the 1024-cycle window), writes at t0 + 16, done t0 + 2048;
//  - tile 2 waits for the window from t0 + 16 to t0 + 2048 - 1024: 1008
//    cycles; writes at t0 + 1040, done t0 + 3072;
//  - tile 3 waits from t0 + 1040 to t0 + 2048: 1008 cycles; writes at
//    t0 + 2064, done t0 + 4096;
//  - the frame ends when that write is done: a tail of 4096 - 2064 = 2032.
// 1008 + 1008 + 2032 = 4048 cycles wait for the l2 port; DRAM moves nothing.
TEST_P(ResolveWriteWindow, WaitsForTheL2PortNotDram) {
  RopConfig c = onePartition(GetParam());
  c.l2.size_bytes = 64 * 1024;
  c.l2.ways = 16;
  c.l2.slices = 1;
  c.l2.bytes_per_clock = 0.25;
  const auto r = alphaFrame(c);
  ASSERT_TRUE(r.ok) << r.error;
  const auto& m = r.stats["memory"];
  ASSERT_EQ(m["dram_read_bytes"]["total"].get<uint64_t>() + m["dram_write_bytes"]["total"].get<uint64_t>(), 0u);
  const auto& l2 = m["levels"][1];
  ASSERT_EQ(l2["name"], "l2");
  EXPECT_EQ(l2["write_bytes"].get<uint64_t>(), 4u * 256);
  EXPECT_EQ(l2["read_bytes"].get<uint64_t>(), 0u);
  const auto& rc = r.stats["timing"]["root_cause_cycles"];
  for (const char* d : {"dram_bandwidth", "dram_latency", "dram_bank_conflict", "dram_turnaround", "dram_refresh"})
    EXPECT_EQ(cause(r, d), 0u) << d << ": " << rc.dump();
  // t0 = the resolve's start + tile 0's lines (ROP-cache hits: hit latency
  // 10, `rop_cache_miss`) + its compute (16, `alu`, as each tile's).
  EXPECT_EQ(r.stats["timing"]["phase_cycles"]["resolve"].get<uint64_t>(), 10u + 16 + 4096);
  EXPECT_EQ(cause(r, "alu"), 4u * 16) << rc.dump();
  if (GetParam() == SimEngine::CycleStepped) {
    EXPECT_EQ(cause(r, "l2"), 1008u + 1008 + 2032) << rc.dump();
  } else {
    // The approximate engine shares its pass's drain out in proportion to
    // the delays its fragments met, the clear fills' among them (their wait
    // beyond DRAM is `l2` when shared levels are configured), where the cycle
    // engine says pipeline_latency: at most the pass (192 cycles) on top.
    EXPECT_GE(cause(r, "l2"), 1008u + 1008 + 2032) << rc.dump();
    EXPECT_LE(cause(r, "l2"), 1008u + 1008 + 2032 + r.stats["timing"]["phase_cycles"]["transparent"][0].get<uint64_t>())
        << rc.dump();
  }
}

// Without shared levels the same writes go to the DRAM controller's write
// queue, which takes them at once (4 x 256 B fit it): no window wait, and the
// frame's tail is the drain of the queue, DRAM's causes (none of it `l2`).
TEST_P(ResolveWriteWindow, WithoutSharedLevelsTheTailIsDram) {
  const auto r = alphaFrame(onePartition(GetParam()));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.stats["memory"]["dram_write_bytes"]["total"].get<uint64_t>(), 4u * 256);
  EXPECT_EQ(cause(r, "l2"), 0u);
  uint64_t dram = 0;
  for (const char* d : {"dram_bandwidth", "dram_latency", "dram_bank_conflict", "dram_turnaround", "dram_refresh"})
    dram += cause(r, d);
  EXPECT_GT(dram, 0u) << r.stats["timing"]["root_cause_cycles"].dump();
}

INSTANTIATE_TEST_SUITE_P(BothEngines, ResolveWriteWindow, ::testing::ValuesIn(kBothEngines), engineName);

}  // namespace
