// Root-cause attribution (oit_rop/RootCause.hpp, DESIGN.md "Root causes"):
// the accounts and the DRAM split derived by hand, and microbenchmarks that
// stress one resource each (the traces of the analytic-bound tests): every
// one must report that resource as timing.bound_by with at least 90 % of the
// partition-cycles, on both engines.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "oit_rop/RootCause.hpp"
#include "oit_rop/RopTestUtil.hpp"
#include "oit_rop/memory/DramTestConfig.hpp"
#include "oit_rop/memory/MemorySystem.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

uint64_t at(const RootCauseAccount& a, RootCause c) { return a.cycles()[size_t(c)]; }

// A wait from 4 to 20 whose DRAM unloaded access ends at 10 and queueing at
// 15: 6 cycles of latency, 5 of bandwidth, 5 of the cache's own; then the
// ALU from 20 to 30.
TEST(RootCauseAccount, AWaitIsChargedByItsParts) {
  RootCauseAccount a;
  a.set(0, RootCause::Input);
  a.setWait(4, WaitSplit{10, 15, 15, RootCause::RopCacheMiss});
  a.set(20, RootCause::Alu);
  a.account(30);
  EXPECT_EQ(at(a, RootCause::Input), 4u);
  EXPECT_EQ(at(a, RootCause::DramLatency), 6u);
  EXPECT_EQ(at(a, RootCause::DramBandwidth), 5u);
  EXPECT_EQ(at(a, RootCause::RopCacheMiss), 5u);
  EXPECT_EQ(at(a, RootCause::Alu), 10u);
  EXPECT_EQ(a.total(), 30u);
  // Only the tail of a wait: from 12 on, 3 cycles of queueing, 2 of transfer
  // (its further data: both bandwidth) and 3 of the L2.
  RootCauseAccount b;
  b.setWait(12, WaitSplit{10, 15, 17, RootCause::L2});
  b.skipTo(12);
  b.account(20);
  EXPECT_EQ(at(b, RootCause::DramBandwidth), 5u);
  EXPECT_EQ(at(b, RootCause::DramLatency), 0u);
  EXPECT_EQ(at(b, RootCause::L2), 3u);
}

// A line ready at 180 asked at 100 whose DRAM read completed at 170, 40
// cycles to its first data and 12 more for the rest on an idle channel: 70
// cycles of DRAM: the latency 40 first (overlapping the bus's older data),
// queueing 18, the transfer 12; the last 10 are the cache's.
TEST(RootCauseAccount, SplitWaitPutsTheUnloadedAccessFirst) {
  const WaitSplit w = splitWait(100, 180, DramProbe{170, 40, 12});
  EXPECT_EQ(w.latency_end, 140u);
  EXPECT_EQ(w.queue_end, 158u);
  EXPECT_EQ(w.dram_end, 170u);
  EXPECT_EQ(w.rest, RootCause::RopCacheMiss);
  // No DRAM request (a fast-clear fill): the whole wait is the cache's.
  const WaitSplit c = splitWait(100, 110, DramProbe{});
  EXPECT_EQ(c.latency_end, 100u);
  EXPECT_EQ(c.dram_end, 100u);
}

// Delays of 3 (lock) and 1 (ALU) share 10 cycles: 7 and 2 whole, the cycle
// left to the larger remainder (both 2/4: the first cause, the lock): 8 and 2.
// With no delay gathered the fallback takes all.
TEST(RootCauseAccount, DelaySharesAddUpExactly) {
  DelayShares s;
  RootCauseAccount a;
  s.add(RootCause::LockWait, 3);
  s.add(RootCause::Alu, 1);
  s.chargeTo(a, 10, RootCause::ScoreboardFull);
  EXPECT_EQ(at(a, RootCause::LockWait), 8u);
  EXPECT_EQ(at(a, RootCause::Alu), 2u);
  s.chargeTo(a, 5, RootCause::ScoreboardFull);  // the delays were used up
  EXPECT_EQ(at(a, RootCause::ScoreboardFull), 5u);
  EXPECT_EQ(a.total(), 15u);
}

// The DRAM's split on the round configuration (DramTestConfig.hpp: controller
// 40, tRCD = CL = 11, a 64 B burst 4 cycles, one channel):
//  - one 64 B read at cycle 0 on an idle channel: 40 + 11 + 11 + 4 = 66, all latency;
//  - a 256 B read: its first burst at 66, three more at the bus's rate: 78,
//    66 latency and 12 bandwidth;
//  - a 64 B read to another bank asked with it: its row opens in parallel, its
//    data waits for the bus until 78: done 82, 66 latency and 16 queueing.
TEST(RootCauseAccount, DramWaitSplitsIntoQueueingAndUnloadedAccess) {
  MemorySystem m(roundDramConfig(1), kRoundMhz);
  ASSERT_EQ(m.unloadedCycles(false), kCtrl + kTrcd + kCl + kBurst);
  m.resetProbe();
  EXPECT_EQ(m.access(0, 0, 64, false, Surface::BlendArrays), 66u);
  EXPECT_EQ(m.probe().done, 66u);
  EXPECT_EQ(m.probe().unloaded, 66u);
  WaitSplit w = splitWait(0, 66, m.probe());
  EXPECT_EQ(w.latency_end, 66u);
  EXPECT_EQ(w.queue_end, 66u);
  EXPECT_EQ(w.dram_end, 66u);

  MemorySystem n(roundDramConfig(1), kRoundMhz);
  n.resetProbe();
  EXPECT_EQ(n.access(0, 0, 256, false, Surface::BlendArrays), 78u);
  EXPECT_EQ(n.probe().transfer, 12u);
  w = splitWait(0, 78, n.probe());
  EXPECT_EQ(w.latency_end, 66u);
  EXPECT_EQ(w.queue_end, 66u);
  EXPECT_EQ(w.dram_end, 78u);  // bandwidth: its own three further bursts
  ASSERT_NE(n.bankOf(8192), n.bankOf(0));
  n.resetProbe();
  EXPECT_EQ(n.access(0, 8192, 64, false, Surface::BlendArrays), 82u);
  w = splitWait(0, 82, n.probe());
  EXPECT_EQ(w.latency_end, 66u);
  EXPECT_EQ(w.queue_end, 82u);  // queued 16 cycles behind the first read's data
  EXPECT_EQ(w.dram_end, 82u);
  // A posted write's latency is the controller's: accepted at 40 on an empty queue.
  n.resetProbe();
  EXPECT_EQ(n.access(0, 1 << 20, 64, true, Surface::BlendArrays), 40u);
  EXPECT_EQ(n.probe().unloaded, 40u);
}

// ---- Microbenchmarks (the traces of tests/oit_rop/test_bounds.cpp) ----

// `layers` fragments per pixel over a w x h frame, each layer a sweep of the
// pixels in raster order, nearer than the last by 1/1024.
std::vector<Fragment> layersOf(uint16_t w, uint16_t h, unsigned layers) {
  std::vector<Fragment> fs;
  for (unsigned l = 0; l < layers; ++l)
    for (uint16_t y = 0; y < h; ++y)
      for (uint16_t x = 0; x < w; ++x)
        fs.push_back(model::testutil::frag(x, y, 0.99f - float(l) / 1024.0f, 0.5f, 0.4f, 0.3f, 0.25f,
                                           model::testutil::kTranspDraw, l * h * w + y * w + x));
  return fs;
}

RopConfig base() {
  RopConfig c = smallConfig();
  c.partitions.count = 1;
  c.input.latency_model = LatencyModel::Fixed;
  c.input.latency_min = 40;
  return c;
}

model::AlgorithmParams rgba8(unsigned layers = 4) {
  model::AlgorithmParams p;
  p.layers = layers;
  p.format = model::StorageFormat::Rgba8T8Z32;
  return p;
}

// bound_by is `cause` with at least 90 % of the partition-cycles; the root
// causes add up to every partition's cycles.
void expectBoundBy(const ChildRun& r, const std::string& cause) {
  const auto& t = r.stats["timing"];
  uint64_t charged = 0, ends = 0;
  for (const auto& [k, v] : t["root_cause_cycles"].items()) charged += v.get<uint64_t>();
  for (const auto& p : t["per_partition"]) ends += p["end_cycle"].get<uint64_t>();
  EXPECT_EQ(charged, ends);
  ::testing::Test::RecordProperty("bound_share", std::to_string(t["bound_by"]["share"].get<double>()));
  EXPECT_EQ(t["bound_by"]["resource"].get<std::string>(), cause) << t["root_cause_cycles"].dump();
  EXPECT_GE(t["bound_by"]["share"].get<double>(), 0.90) << t["root_cause_cycles"].dump();
  EXPECT_DOUBLE_EQ(t["bound_by"]["share"].get<double>(), double(t["root_cause_cycles"][cause].get<uint64_t>()) / double(charged));
}

class RootCauses : public ::testing::TestWithParam<SimEngine> {};

// 65 536 fragments at 1 per clock into 4 blends per clock: the input.
TEST_P(RootCauses, InputBoundTraceIsBoundByTheInput) {
  RopConfig c = base();
  c.sim.engine = GetParam();
  c.input.fragments_per_clock = 1.0;
  c.alu.blends_per_clock = 4;
  const auto r = runInChild([&] { return timed("alpha", rgba8(), layersOf(16, 16, 256), 16, 16, c); });
  ASSERT_TRUE(r.ok) << r.error;
  expectBoundBy(r, "input");
  // The input's utilisation: 65 536 fragments over about as many cycles.
  EXPECT_GT(r.stats["timing"]["utilization"]["input"].get<double>(), 0.95);
}

// The same at 4 fragments per clock into 1 blend per clock: the ALU.
TEST_P(RootCauses, AluBoundTraceIsBoundByTheAlu) {
  RopConfig c = base();
  c.sim.engine = GetParam();
  c.input.fragments_per_clock = 4.0;
  c.alu.blends_per_clock = 1;
  const auto r = runInChild([&] { return timed("alpha", rgba8(), layersOf(16, 16, 256), 16, 16, c); });
  ASSERT_TRUE(r.ok) << r.error;
  expectBoundBy(r, "alu");
  EXPECT_GT(r.stats["timing"]["utilization"]["alu"].get<double>(), 0.95);
}

// 4096 fragments to one pixel, a release every 20 cycles: the lock.
TEST_P(RootCauses, OnePixelTraceIsBoundByTheLock) {
  RopConfig c = base();
  c.sim.engine = GetParam();
  c.input.fragments_per_clock = 2.0;
  c.alu.blends_per_clock = 4;
  const auto r = runInChild([&] { return timed("alpha", rgba8(), layersOf(1, 1, 4096), 8, 8, c); });
  ASSERT_TRUE(r.ok) << r.error;
  expectBoundBy(r, "lock_wait");
}

// mlab k = 8 (64 B per pixel: a 4 KiB tile line) over 64x32 pixels, four
// layers, through a ROP cache of 16 lines (a layer sweeps 32 tiles) into one
// DDR3-1600 channel: every tile of every layer misses and writes back its
// dirty line; the input (4 per clock) and the ALU (4) are far faster than the
// bus (11.1 B per cycle: a line in 368 cycles for 64 fragments).
TEST_P(RootCauses, StreamingTraceIsBoundByDramBandwidth) {
  RopConfig c = base();
  c.sim.engine = GetParam();
  c.cache.size_bytes = 64 * 1024;
  c.input.fragments_per_clock = 4.0;
  c.alu.blends_per_clock = 4;
  c.dram.channels = 1;
  const auto r = runInChild([&] { return timed("mlab", rgba8(8), layersOf(64, 32, 4), 64, 32, c); });
  ASSERT_TRUE(r.ok) << r.error;
  expectBoundBy(r, "dram_bandwidth");
  EXPECT_GT(r.stats["timing"]["utilization"]["dram_bus"].get<double>(), 0.85);
}

INSTANTIATE_TEST_SUITE_P(Microbenchmarks, RootCauses, ::testing::ValuesIn(kBothEngines), engineName);

}  // namespace
